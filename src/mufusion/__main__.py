"""``python -m mufusion``: the command line, also where the ``mufusion`` script is not on PATH."""

from mufusion.cli import app

app(prog_name="mufusion")
