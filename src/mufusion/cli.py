"""The ``mufusion`` command line.

Subcommands are registered here; each one is a thin layer over the library (validation of the
arguments, a progress bar, files written), never physics or estimation of its own.
"""

from __future__ import annotations

import typer

app = typer.Typer(
    name="mufusion",
    help=(
        "Friction-estimate fusion for traction-adaptive motion planning: reproduce the paper's "
        "experiments, run scenarios in closed loop and inspect the GP fusion."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _main() -> None:
    """mufusion: fuse camera and slip-based friction estimates and drive on them in closed loop."""


if __name__ == "__main__":  # pragma: no cover
    app()
