"""Kajita's ZMP preview control of the cart-table model (extended, integral-action form), x and y at once."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import solve_discrete_are

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.core.types import read_only


@dataclass(frozen=True)
class PreviewControlParams(Params):
    dt_s: float = field(default=0.005, metadata={"unit": "s", "min": 1e-4, "max": 0.1})
    com_height_m: float = field(default=0.8, metadata={"unit": "m", "min": 0.05, "max": 5.0})  # z_c
    gravity_m_s2: float = field(default=GRAVITY_M_S2, metadata={"unit": "m/s^2", "min": 0.1, "max": 100.0})
    preview_time_s: float = field(default=1.6, metadata={"unit": "s", "min": 0.0, "max": 10.0})
    # cost weights of Eq. 5: q on the ZMP error, r on the jerk increment
    q: float = field(default=1.0, metadata={"unit": "1/m^2", "min": 1e-12, "max": 1e12})
    r: float = field(default=1e-6, metadata={"unit": "s^6/m^2", "min": 1e-15, "max": 1e12})

    @property
    def preview_length(self) -> int:
        """N = round(preview_time / dt) samples of future reference ZMP."""
        return max(1, round(self.preview_time_s / self.dt_s))


@dataclass(frozen=True)
class PreviewGains:
    """Gains of the extended cart-table preview controller, shared by the x and y axes.

    Incremental law (Katayama 1985, Kajita 2003):
    du_k = -ks e_k - kx . (x_k - x_{k-1}) + sum_{j=1..N} f_j (p_ref_{k+j} - p_ref_{k+j-1}),
    with e_k = C x_k - p_ref_k, u the COG jerk and x = (position, velocity, acceleration).
    """

    A: np.ndarray  # (3, 3) cart-table transition
    B: np.ndarray  # (3,) jerk input [m/s^3 -> state]
    C: np.ndarray  # (3,) state -> cart-table ZMP
    P: np.ndarray  # (4, 4) solution of the DARE of the extended model
    ks: float  # gain on the ZMP error e_k [m/s^3 per m]
    kx: np.ndarray  # (3,) gain on the state increment
    f: np.ndarray  # (N,) preview gains f_1..f_N on future reference increments

    def __repr__(self) -> str:
        return f"PreviewGains(ks={self.ks:.6g}, kx={np.array2string(self.kx, precision=6)}, N={self.f.size})"


def cart_table_matrices(dt_s: float, com_height_m: float, gravity_m_s2: float):
    """Discrete cart-table model x+ = A x + B u, zmp = C x, with x = (pos, vel, acc) and u the jerk."""
    A = np.array([[1.0, dt_s, dt_s**2 / 2.0], [0.0, 1.0, dt_s], [0.0, 0.0, 1.0]])
    B = np.array([dt_s**3 / 6.0, dt_s**2 / 2.0, dt_s])
    C = np.array([1.0, 0.0, -com_height_m / gravity_m_s2])
    return A, B, C


def preview_gains(params: PreviewControlParams) -> PreviewGains:
    """Solve the extended model's discrete algebraic Riccati equation once and derive all gains."""
    A, B, C = cart_table_matrices(params.dt_s, params.com_height_m, params.gravity_m_s2)
    # extended state (e_k, dx_k): e+ = e + C A dx + C B du - dp_ref, dx+ = A dx + B du
    A_e = np.zeros((4, 4))
    A_e[0, 0] = 1.0
    A_e[0, 1:] = C @ A
    A_e[1:, 1:] = A
    B_e = np.concatenate(([C @ B], B)).reshape(4, 1)
    Q_e = np.diag([params.q, 0.0, 0.0, 0.0])
    R_e = np.array([[params.r]])
    P = solve_discrete_are(A_e, B_e, Q_e, R_e)
    den = params.r + (B_e.T @ P @ B_e).item()
    K = (B_e.T @ P @ A_e).ravel() / den  # (4,)
    Ac_T = (A_e - B_e @ K.reshape(1, 4)).T
    n = params.preview_length
    f = np.empty(n)
    v = P[:, 0].copy()  # (Ac^T)^(j-1) P I, I = (1, 0, 0, 0)
    for j in range(n):
        f[j] = (B_e.ravel() @ v) / den
        v = Ac_T @ v
    for a in (A, B, C, P, f):
        read_only(a)
    kx = read_only(K[1:].copy())
    return PreviewGains(A=A, B=B, C=C, P=P, ks=float(K[0]), kx=kx, f=f)


class PreviewQueue:
    """Fixed-length queue of the next N reference ZMPs [m], oldest (next tick) first.

    A doubled ring buffer keeps the N rows contiguous, so `push` is O(1) and `view` copies nothing.
    """

    def __init__(self, length: int, zmp_world_xy=(0.0, 0.0)) -> None:
        if length < 1:
            raise InvalidCommand(f"PreviewQueue length={length}; use a length of 1 or more")
        self.length = length
        self._buf = np.empty((2 * length, 2))  # (2N, 2) [m]
        self.fill(zmp_world_xy)

    def fill(self, zmp_world_xy) -> None:
        """Every future reference equals `zmp_world_xy` [m] (standing still)."""
        self._buf[:] = np.asarray(zmp_world_xy, dtype=float).reshape(2)
        self._head = 0

    def push(self, zmp_world_xy) -> None:
        """Drop the oldest reference and append `zmp_world_xy` [m], the reference N ticks ahead."""
        h, n = self._head, self.length
        self._buf[h] = zmp_world_xy
        self._buf[h + n] = zmp_world_xy
        self._head = h + 1 if h + 1 < n else 0

    @property
    def view(self) -> np.ndarray:
        """(N, 2) read-only view, row j = the reference ZMP j + 1 ticks ahead [m]."""
        return read_only(self._buf[self._head : self._head + self.length])

    def __len__(self) -> int:
        return self.length


class PreviewController:
    """Per-tick COG from the future reference ZMP; x and y share the gains and run as two columns.

    State `x` is (3, 2): rows are COG position [m], velocity [m/s], acceleration [m/s^2]; columns x, y.
    """

    def __init__(self, params: PreviewControlParams | None = None) -> None:
        self.params = params if params is not None else PreviewControlParams()
        self.gains = preview_gains(self.params)
        g = self.gains
        n = self.params.preview_length
        # sum_j f_j (r_j - r_{j-1}) with r_0 the previous reference = w . rows - f_1 r_0
        f_next = np.append(g.f[1:], 0.0)
        self._w = g.f - f_next  # (N,)
        self._f1 = float(g.f[0])
        self._A = np.array(g.A)
        self._B = g.B.reshape(3, 1)
        self._C = g.C
        self._ks = g.ks
        self._kx = g.kx.reshape(3, 1)
        self._n = n
        self.reset(np.zeros(2))

    def __repr__(self) -> str:
        return f"PreviewController({self.params!r}, {self.gains!r})"

    @property
    def preview_length(self) -> int:
        """N, the number of future reference ZMPs `update` expects."""
        return self._n

    def reset(self, com_world_xy, com_vel_world_xy=(0.0, 0.0)) -> None:
        """Start from COG (x, y) [m] moving at (vx, vy) [m/s], zero acceleration and jerk."""
        self.x = np.zeros((3, 2))  # (3, 2) pos [m], vel [m/s], acc [m/s^2]
        self.x[0] = np.asarray(com_world_xy, dtype=float).reshape(2)
        self.x[1] = np.asarray(com_vel_world_xy, dtype=float).reshape(2)
        self._dx = np.zeros((3, 2))  # x_k - x_{k-1}
        self._dx[0] = self.x[1] * self.params.dt_s
        self._u = np.zeros(2)  # COG jerk [m/s^3]
        self._zmp_ref_prev = self._C @ self.x  # (2,) reference of the current tick [m]

    @property
    def zmp_cart_world_xy(self) -> np.ndarray:
        """Cart-table ZMP of the current state, x - z_c/g * xddot [m]."""
        return self._C @ self.x

    def update(self, zmp_ref_future_world_xy: np.ndarray):
        """Advance one dt. `zmp_ref_future_world_xy` (N, 2): row j = reference ZMP j + 1 ticks ahead [m].

        Returns (com_pos, com_vel, com_acc, zmp_cart), each (2,), at the new tick; zmp_cart tracks row 0.
        """
        r = zmp_ref_future_world_xy
        if r.shape != (self._n, 2):
            raise InvalidCommand(f"zmp_ref_future shape {r.shape}; expected ({self._n}, 2)")
        x = self.x
        e = self._C @ x - self._zmp_ref_prev  # (2,)
        du = self._w @ r - self._f1 * self._zmp_ref_prev - self._ks * e - np.add.reduce(self._kx * self._dx, axis=0)
        self._u = self._u + du
        x_new = self._A @ x + self._B * self._u
        self._dx = x_new - x
        self.x = x_new
        self._zmp_ref_prev = r[0].copy()
        return x_new[0], x_new[1], x_new[2], self._C @ x_new
