"""The identification's report: one self-contained HTML page (``DIR/report.html``) beside the JSON
and CSV the folder already holds (docs/identification.md#the-report).

What it shows, from ``identification.json`` and the held-out segment's torques: the robot, the
log and its segments; the identifiability (condition number, unexcited or held parameters); the
physical checks; per joint, the held-out torque logged against the one the physically consistent
model predicts, and the residual's share of the torque RMS for the URDF's model, the least
squares and the physical model on both segments; each joint's identified friction curve over the
log's speeds; and the parameter table with its confidence intervals. The figures are PNGs inside
the page (no file beside it), drawn with the package's Agg backend.
"""

from __future__ import annotations

import base64
import html
import io

import numpy as np

MAX_POINTS = 4000
"""Samples per joint the torque figure draws (a long log is thinned evenly)."""


def _png(fig) -> str:
    from ...outputs.plots import plt

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return f'<img alt="figure" src="data:image/png;base64,{base64.b64encode(buffer.getvalue()).decode()}">'


def torque_figure(t: np.ndarray, logged: np.ndarray, predicted: np.ndarray, joints) -> str:
    """The held-out torque logged and predicted, one panel per joint (an <img>)."""
    from ...outputs.plots import plt

    step = max(1, len(t) // MAX_POINTS)
    n = logged.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.5 * n + 0.6), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(t[::step], logged[::step, j], lw=0.8, color="0.3", label="logged")
        ax.plot(t[::step], predicted[::step, j], lw=0.8, color="tab:red", label="physical model")
        ax.set_ylabel(f"{joints[j]}\n[N m]", fontsize="small")
    axes[0, 0].legend(fontsize="small", loc="upper right", ncol=2)
    axes[-1, 0].set_xlabel("time [s] (held-out segment)")
    return _png(fig)


def share_figure(summary: dict) -> str:
    """Each joint's residual RMS / torque RMS, per model and segment (an <img>)."""
    from ...outputs.plots import plt

    joints = summary["joints"]
    kinds = (("urdf", "URDF"), ("least_squares", "least squares"), ("physical", "physical"))
    fig, axes = plt.subplots(1, 2, figsize=(8.0, 2.8), sharey=True)
    x = np.arange(len(joints))
    for ax, segment, title in ((axes[0], "fit", "fit segment"), (axes[1], "held_out", "held out")):
        torque = np.asarray(summary["torque_rms"][segment])
        for k, (key, label) in enumerate(kinds):
            share = np.asarray(summary["residuals"][key][f"{segment}_rms"]) / torque
            ax.bar(x + (k - 1) * 0.27, 100 * share, 0.27, label=label)
        ax.set_xticks(x, joints, rotation=45, ha="right", fontsize="small")
        ax.set_title(title, fontsize="medium")
    axes[0].set_ylabel("residual / torque RMS [%]")
    axes[0].set_yscale("log")  # the URDF's residual can be 100 times the fitted models'
    axes[1].legend(fontsize="small")
    return _png(fig)


def friction_figure(summary: dict, speeds: np.ndarray) -> str:
    """Each joint's identified friction torque over the log's speeds (an <img>; ``speeds``: rows
    of joint speeds, the largest in magnitude of each column is the axis' reach).
    """
    from ...outputs.plots import plt

    joints, friction = summary["joints"], summary["friction"]
    n = len(joints)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(2.2 * cols + 0.5, 1.9 * rows + 0.4), squeeze=False)
    for j in range(rows * cols):
        ax = axes[j // cols, j % cols]
        if j >= n:
            ax.axis("off")
            continue
        top = max(float(np.nanmax(np.abs(speeds[:, j]))), 1e-3)
        v = np.linspace(-top, top, 201)
        f = np.zeros_like(v)
        f += friction.get("viscous", [0.0] * n)[j] * v
        f += friction.get("coulomb", [0.0] * n)[j] * np.sign(v)
        f += friction.get("offset", [0.0] * n)[j]
        ax.plot(v, f, color="tab:blue")
        ax.axhline(0, color="0.8", lw=0.5)
        ax.axvline(0, color="0.8", lw=0.5)
        ax.set_title(joints[j], fontsize="small")
        ax.tick_params(labelsize="x-small")
    fig.supxlabel("joint speed in the log [rad/s]", fontsize="small")
    fig.supylabel("friction [N m]", fontsize="small")
    return _png(fig)


def _table(rows: list[list[str]], header: list[str]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def report_html(summary: dict, held_t: np.ndarray, logged: np.ndarray, predicted: np.ndarray, speeds) -> str:
    """The page (module docstring)."""
    ident, checks, region = summary["identifiability"], summary["checks"], summary["confidence"]
    log = summary["log"]
    facts = [
        ["robot", summary["robot"]],
        ["log", str(log["source"])],
        ["fit segment [s]", "{:.4g} to {:.4g}".format(*summary["segments"]["fit"])],
        ["held-out segment [s]", "{:.4g} to {:.4g}".format(*summary["segments"]["held_out"])],
        [
            "base parameters",
            f"{ident['base_parameters']} (+ {ident['parameters'] - ident['base_parameters']} "
            "friction and armature terms)",
        ],  # fmt: skip
        ["condition number", f"{ident['condition_number']:.4g}"],
        ["unexcited", ", ".join(ident["unexcited"]) or "none"],
        ["armature held at the URDF's", ", ".join(ident.get("armature_held", [])) or "none"],
        [
            "physical",
            f"yes (least M(q) eigenvalue {checks['mass_matrix_least_eigenvalue']:.3g})"
            if checks["physical"]
            else "no",
        ],  # fmt: skip
        ["confidence region", f"{100 * region['level']:g} %: {region['method']}"],
    ]
    held = summary["residuals"]["physical"]["held_out_share"]
    joints_rows = [
        [name, f"{summary['torque_rms']['held_out'][j]:.3f}", f"{100 * held[j]:.1f} %",
         f"{100 * summary['residuals']['urdf']['held_out_share'][j]:.1f} %"]
        for j, name in enumerate(summary["joints"])
    ]  # fmt: skip
    parameters = [
        [p["name"], f"{p['least_squares']:.5g}", f"{p['standard_error']:.3g}",
         f"[{p['low']:.5g}, {p['high']:.5g}]", f"{p['physical']:.5g}"]
        for p in summary["parameters"]
    ]  # fmt: skip
    warnings = "".join(f"<li>{html.escape(w)}</li>" for w in summary["warnings"]) or "<li>none</li>"
    style = (
        "body{font-family:sans-serif;max-width:60em;margin:2em auto;color:#222}"
        "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.2em .6em;"
        "text-align:left;font-size:.9em}img{max-width:100%}"
    )
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>identification: "
        f"{html.escape(summary['robot'])}</title><style>{style}</style></head><body>"
        f"<h1>Identification of {html.escape(summary['robot'])}</h1>"
        + _table(facts, ["", ""])
        + "<h2>Warnings</h2><ul>" + warnings + "</ul>"
        + "<h2>Held-out torque</h2>"
        + _table(joints_rows, ["joint", "torque RMS [N m]", "physical model's residual", "URDF's residual"])
        + torque_figure(held_t, logged, predicted, summary["joints"])
        + "<h2>Residual per model and segment</h2>" + share_figure(summary)
        + "<h2>Friction</h2>" + friction_figure(summary, speeds)
        + "<h2>Parameters</h2><p>Base parameters (least squares, their standard errors and "
        f"{100 * region['level']:g} % intervals) and the physically consistent model's value of each.</p>"
        + _table(parameters, ["parameter", "least squares", "standard error", "interval", "physical"])
        + f"<p>nnrobust {html.escape(summary['version'])}; the numbers are identification.json's.</p>"
        "</body></html>\n"
    )  # fmt: skip
