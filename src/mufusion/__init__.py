"""mufusion: fusion of heterogeneous friction estimates for traction-adaptive motion planning.

The package is laid out along the data flow
``road -> vehicle -> estimators -> fusion -> planner -> sim -> scenarios / metrics / plots / cli``;
imports only point upstream.
"""

from __future__ import annotations

__version__ = "0.1.0"

__all__ = ["__version__"]
