"""``python -m nnrobust.cli``: the ``nnrobust`` command (its stop handlers are installed by
:func:`nnrobust.cli.run` before the commands' modules are imported).
"""

from . import run

if __name__ == "__main__":
    run()
