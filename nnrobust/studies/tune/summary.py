"""A tuning's summary.json as a rich display in Jupyter: each controller's best setting, its
training and held-out error and torque, and whether it is feasible on the held-out draws.
"""

from __future__ import annotations

import html

from ..base.display import html_cell, table


class TuneSummary(dict):
    """A tuning's summary.json: each controller's best setting, its training and held-out error."""

    def _repr_html_(self) -> str:
        rows = []
        for name, e in self["controllers"].items():
            best = e.get("best") or {}
            setting = ", ".join(
                f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                for k, v in (best.get("params") or {}).items()
            )
            rows.append(
                [
                    html.escape(name),
                    html_cell((best.get("train") or {}).get("rms_error_after_2s"), 1e3),
                    html_cell((best.get("train") or {}).get("rms_torque")),
                    html_cell((best.get("validation") or {}).get("rms_error_after_2s"), 1e3),
                    html_cell((best.get("validation") or {}).get("rms_torque")),
                    html_cell(best.get("validation_feasible")),
                    html.escape(setting or e.get("note", "")),
                ]
            )
        target = html.escape(str(self.get("target")))
        out = f"<h4>tuning of {target}: {self.get('budget')} simulations each</h4>"
        head = ["controller", "training e [mm]", "training rms tau [N m]", "held-out e [mm]",
                "held-out rms tau [N m]", "feasible on held-out", "best setting"]  # fmt: skip
        return out + table(head, rows)
