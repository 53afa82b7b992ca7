"""Package attributes imported on first use (PEP 562), for packages whose light parts a command
reads before it needs the heavy ones.

A command refused for bad input (a scenario file with a typo) must answer in well under a second;
importing SciPy, pandas and the planner first took 3 s (docs/performance.md, "Input errors").
A package lists the submodule of each lazily exported name; its ``if TYPE_CHECKING`` imports
give type checkers the same names.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping


def lazy_getattr(package: str, exports: Mapping[str, str]) -> Callable[[str], object]:
    """A module-level ``__getattr__`` that imports ``package.<exports[name]>`` on first access.

    Parameters
    ----------
    package
        The package's ``__name__``.
    exports
        Exported name → the submodule (relative to ``package``) that defines it.

    Returns
    -------
    callable
        ``__getattr__(name)``; raises ``AttributeError`` for a name not in ``exports``.

    Examples
    --------
    >>> get = lazy_getattr("mufusion.sim", {"load_run": "log"})
    >>> get("load_run").__module__
    'mufusion.sim.log'
    """

    def __getattr__(name: str) -> object:
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{exports[name]}"), name)

    return __getattr__
