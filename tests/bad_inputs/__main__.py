"""``python -m tests.bad_inputs``: docs/bad-inputs.md from the messages the cases raise."""

import tempfile
from pathlib import Path

from . import render_table

with tempfile.TemporaryDirectory() as tmp:
    Path("docs/bad-inputs.md").write_text(render_table(Path(tmp)))
print("wrote docs/bad-inputs.md")
