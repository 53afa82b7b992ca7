from collections.abc import Callable

import numpy as np

def rollouts(
    xs: np.ndarray,
    us: np.ndarray,
    d_t: np.ndarray,
    v_t: np.ndarray,
    curvature_of_s: Callable[[np.ndarray], np.ndarray | float],
    mu_hat_of_s: Callable[[np.ndarray], np.ndarray | float],
    stiffness_of: Callable[[np.ndarray, np.ndarray], np.ndarray] | None,
    constants: tuple[float, ...],
    stiffness_per_load: float = 0.0,
) -> None: ...
