"""Type stubs of the compiled module kinema._core (private: use the documented kinema API)."""

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str

class ButcherTableau:
    """An explicit Runge-Kutta method (A, b, c), checked when built."""

    def __init__(self, a: Sequence[Sequence[float]], b: Sequence[float], c: Sequence[float], order: int, name: str = "custom") -> None: ...
    @staticmethod
    def of(method: str) -> ButcherTableau: ...
    @property
    def name(self) -> str: ...
    @property
    def order(self) -> int: ...
    @property
    def stages(self) -> int: ...
    @property
    def A(self) -> npt.NDArray[np.float64]: ...
    @property
    def b(self) -> npt.NDArray[np.float64]: ...
    @property
    def c(self) -> npt.NDArray[np.float64]: ...
    def stability_polynomial(self) -> npt.NDArray[np.float64]: ...

class DenseOutput:
    """The continuous solution of a solve with dense_output."""

    def __call__(self, t: list[float]) -> npt.NDArray[np.float64]: ...
    @property
    def span(self) -> tuple[float, float]: ...

def methods() -> list[dict[str, Any]]: ...
def solve(
    f: Callable[..., Any],
    y0: npt.NDArray[np.float64],
    t_span: tuple[float, float],
    h: float | None,
    h_max: float | None,
    method: str | ButcherTableau,
    jac: Callable[..., Any] | None,
    rtol: float,
    atol: float,
    t_eval: list[float] | None,
    vectorized: bool,
    dense_output: bool,
) -> dict[str, Any]: ...
def solve_second_order(
    a: Callable[..., Any],
    x0: npt.NDArray[np.float64],
    v0: npt.NDArray[np.float64],
    t_span: tuple[float, float],
    h: float | None,
    h_max: float | None,
    method: str | ButcherTableau,
    rtol: float,
    atol: float,
    t_eval: list[float] | None,
    vectorized: bool,
    dense_output: bool,
) -> dict[str, Any]: ...
def amplification(method: str | ButcherTableau, z: npt.NDArray[np.complex128]) -> npt.NDArray[np.complex128]: ...
def max_step(method: str | ButcherTableau, lam: npt.NDArray[np.complex128]) -> npt.NDArray[np.float64]: ...
def real_interval(method: str | ButcherTableau) -> tuple[float, float]: ...
def imag_interval(method: str | ButcherTableau) -> tuple[float, float]: ...
def oscillator_max_step(method: str | ButcherTableau, omega: float, zeta: float) -> float: ...
def oscillator_amplification(method: str | ButcherTableau, h: float, omega: float, zeta: float) -> float: ...
