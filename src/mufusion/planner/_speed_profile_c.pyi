import numpy as np

def backward_pass(
    u: np.ndarray,
    kappa: np.ndarray,
    accel: np.ndarray,
    s: np.ndarray,
    two_b: float,
    p: float = ...,
    hl: float = ...,
    g: float = ...,
) -> None: ...
def forward_pass(
    out: np.ndarray,
    cap: np.ndarray,
    kappa: np.ndarray,
    accel: np.ndarray,
    s: np.ndarray,
    w: float,
    bottom: int,
    max_accel: float,
) -> None: ...
def descent_pass(
    out: np.ndarray,
    floor: np.ndarray,
    kappa: np.ndarray,
    accel: np.ndarray,
    s: np.ndarray,
    w: float,
    fraction: float,
    p: float = ...,
    hl: float = ...,
    g: float = ...,
) -> None: ...
