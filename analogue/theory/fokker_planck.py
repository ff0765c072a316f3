"""Exponentially fitted (Scharfetter-Gummel) discretisation of the Fokker-Planck operator.

``dp/dt = d/dv [U'(v) p + (1/gamma) dp/dv]`` on a uniform grid with ``v = 0`` on a node becomes
a nearest-neighbour master equation with rates

    k(i -> i+1) = B(gamma (U_{i+1} - U_i)) / (gamma h^2),
    k(i+1 -> i) = B(gamma (U_i - U_{i+1})) / (gamma h^2),     B(x) = x / (e^x - 1),

which satisfy detailed balance with respect to ``pi_i ~ exp(-gamma U_i)`` *exactly* (the drift
enters only through differences of U at neighbouring nodes), so the discrete stationary state
is the exact stationary law of the paper (eq. (6)) sampled at the nodes, for the ``sgn``
law and for the smooth ``tanh`` law alike.  Reflecting ends.  The generator is tridiagonal and
similar to the symmetric matrix ``S = Pi^{-1/2} L Pi^{1/2}`` (cf. Holubec, Kroy, Steffenoni,
PRE 99, 032117 (2019)).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse

from .. import checks
from ..model import Model

__all__ = ["Grid", "bernoulli", "generator", "symmetric_generator"]


@dataclass(frozen=True)
class Grid:
    """Uniform grid ``v_i = i h`` for ``i = i_min .. i_max`` (so v = 0 is always a node)."""

    h: float
    i_min: int
    i_max: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "h", checks.positive("grid spacing h", self.h))
        if not self.i_min < 0 < self.i_max:
            raise ValueError("grid must contain v = 0 strictly inside (i_min < 0 < i_max)")

    @property
    def v(self) -> np.ndarray:
        return self.h * np.arange(self.i_min, self.i_max + 1, dtype=float)

    @property
    def n(self) -> int:
        return self.i_max - self.i_min + 1

    @property
    def zero(self) -> int:
        """Index of the node v = 0."""
        return -self.i_min

    @classmethod
    def span(cls, lo: float, hi: float, h: float) -> Grid:
        """Smallest grid of spacing h covering [lo, hi] (extended to contain 0 inside)."""
        return cls(h, min(int(math.floor(lo / h)), -1), max(int(math.ceil(hi / h)), 1))


def bernoulli(x: ArrayLike) -> np.ndarray:
    """``B(x) = x/(e^x - 1)``, accurate near 0 and for large |x|."""
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    small = np.abs(x) < 1e-6
    xs = x[small]
    out[small] = 1.0 - xs / 2.0 + xs * xs / 12.0
    xl = x[~small]
    with np.errstate(over="ignore"):  # x -> +inf: B -> 0 (far tails of exp(-gamma U))
        out[~small] = xl / np.expm1(xl)
    return out


def _rates(model: Model, grid: Grid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward rates k(i->i+1) and backward rates k(i+1->i) on the n-1 links."""
    u = model.gamma * model.potential(grid.v)
    du = np.diff(u)
    c = 1.0 / (model.gamma * grid.h**2)
    return c * bernoulli(du), c * bernoulli(-du), u


def generator(model: Model, grid: Grid) -> sparse.csr_matrix:
    """Forward generator L (``dp/dt = L p`` for the vector of node probabilities)."""
    up, down, _ = _rates(model, grid)
    diag = np.zeros(grid.n)
    diag[:-1] -= up
    diag[1:] -= down
    return sparse.diags([down, diag, up], [1, 0, -1], format="csr")


def symmetric_generator(model: Model, grid: Grid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(diag, offdiag, log_pi)`` of the symmetric tridiagonal ``Pi^{-1/2} L Pi^{1/2}``.

    ``log_pi`` is ``-gamma U`` at the nodes (unnormalised); eigenvalues are those of L.
    Adding ``k F v`` to ``diag`` gives the symmetrised tilted generator of the work.
    """
    up, down, u = _rates(model, grid)
    diag = np.zeros(grid.n)
    diag[:-1] -= up
    diag[1:] -= down
    off = np.sqrt(up * down)
    return diag, off, -u
