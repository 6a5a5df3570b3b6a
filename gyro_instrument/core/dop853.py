"""DOP853 on a small state held in Python floats (``integrate(..., method="DOP853-scalar")``).

A state of three components with a right-hand side of a few sines (the directing-plane
gyroscope's reduced model) spends nearly all of its time in ``solve_ivp`` on per-step overhead
of numpy calls on length-3 arrays (~90 µs per step, 15 RHS calls per step through two
wrappers). This driver runs the same method with plain floats (~18 µs per step): scipy's DOP853
tableau (Hairer's 8(5,3) pair, held below as the public ``scipy.integrate.DOP853`` class has it), the same
initial-step choice, error norm, step-size control and 7th-order dense output, so it takes the
same steps and the same number of RHS evaluations and agrees with ``integrate(...,
method="DOP853")`` to rounding (≤ 1e-13 rad in u over an hour of quet_paris, against the
~1e-10 rad integration error at rtol 1e-11). The stage arithmetic is generated once per state
size with the coefficients as literals; the dense output is evaluated for all sample times at
once after the run. Model: scipy's ``scipy/integrate/_ivp/rk.py`` (``RungeKutta._step_impl``,
``Dop853DenseOutput``) and ``scipy/integrate/_ivp/common.py`` (``select_initial_step``).
"""

import math

import numpy as np

from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

# The DOP853 tableau: Hairer's 8(5,3) Runge-Kutta pair with its 7th-order dense output (E. Hairer,
# S. P. Norsett, G. Wanner, "Solving Ordinary Differential Equations I", 2nd ed., Springer 1993,
# sec. II.10, and the Fortran code dop853.f, http://www.unige.ch/~hairer/software.html), as the
# doubles of scipy's ``scipy/integrate/_ivp/dop853_coefficients.py`` that the public class
# ``scipy.integrate.DOP853`` exposes (A, B, C, E3, E5, D, A_EXTRA, C_EXTRA, n_stages, order,
# error_estimator_order): tests/test_dop853_tableau.py checks that they are equal, value for value.
# Held here so that the parareal fast path does not import scipy.integrate (0.25-0.4 s of import
# on the command line: it loads scipy.optimize, scipy.sparse and scipy.linalg). The rows of A,
# A_EXTRA and D list their non-zero entries (column: value).
_A_ROWS = (
    {},
    {0: 0.05260015195876773},
    {0: 0.0197250569845379, 1: 0.0591751709536137},
    {0: 0.02958758547680685, 2: 0.08876275643042054},
    {0: 0.2413651341592667, 2: -0.8845494793282861, 3: 0.924834003261792},
    {0: 0.037037037037037035, 3: 0.17082860872947386, 4: 0.12546768756682242},
    {0: 0.037109375, 3: 0.17025221101954405, 4: 0.06021653898045596, 5: -0.017578125},
    {0: 0.03709200011850479, 3: 0.17038392571223998, 4: 0.10726203044637328, 5: -0.015319437748624402, 6:
     0.008273789163814023},
    {0: 0.6241109587160757, 3: -3.3608926294469414, 4: -0.868219346841726, 5: 27.59209969944671, 6:
     20.154067550477894, 7: -43.48988418106996},
    {0: 0.47766253643826434, 3: -2.4881146199716677, 4: -0.590290826836843, 5: 21.230051448181193, 6:
     15.279233632882423, 7: -33.28821096898486, 8: -0.020331201708508627},
    {0: -0.9371424300859873, 3: 5.186372428844064, 4: 1.0914373489967295, 5: -8.149787010746927, 6:
     -18.52006565999696, 7: 22.739487099350505, 8: 2.4936055526796523, 9: -3.0467644718982196},
    {0: 2.273310147516538, 3: -10.53449546673725, 4: -2.0008720582248625, 5: -17.9589318631188, 6:
     27.94888452941996, 7: -2.8589982771350235, 8: -8.87285693353063, 9: 12.360567175794303, 10:
     0.6433927460157636},
)
_A_EXTRA_ROWS = (
    {0: 0.056167502283047954, 6: 0.25350021021662483, 7: -0.2462390374708025, 8: -0.12419142326381637, 9:
     0.15329179827876568, 10: 0.00820105229563469, 11: 0.007567897660545699, 12: -0.008298},
    {0: 0.03183464816350214, 5: 0.028300909672366776, 6: 0.053541988307438566, 7: -0.05492374857139099, 10:
     -0.00010834732869724932, 11: 0.0003825710908356584, 12: -0.00034046500868740456, 13:
     0.1413124436746325},
    {0: -0.42889630158379194, 5: -4.697621415361164, 6: 7.683421196062599, 7: 4.06898981839711, 8:
     0.3567271874552811, 12: -0.0013990241651590145, 13: 2.9475147891527724, 14: -9.15095847217987},
)
_D_ROWS = (
    {0: -8.428938276109013, 5: 0.5667149535193777, 6: -3.0689499459498917, 7: 2.38466765651207, 8:
     2.117034582445028, 9: -0.871391583777973, 10: 2.2404374302607883, 11: 0.6315787787694688, 12:
     -0.08899033645133331, 13: 18.148505520854727, 14: -9.194632392478356, 15: -4.436036387594894},
    {0: 10.427508642579134, 5: 242.28349177525817, 6: 165.20045171727028, 7: -374.5467547226902, 8:
     -22.113666853125306, 9: 7.733432668472264, 10: -30.674084731089398, 11: -9.332130526430229, 12:
     15.697238121770845, 13: -31.139403219565178, 14: -9.35292435884448, 15: 35.81684148639408},
    {0: 19.985053242002433, 5: -387.0373087493518, 6: -189.17813819516758, 7: 527.8081592054236, 8:
     -11.57390253995963, 9: 6.8812326946963, 10: -1.0006050966910838, 11: 0.7777137798053443, 12:
     -2.778205752353508, 13: -60.19669523126412, 14: 84.32040550667716, 15: 11.99229113618279},
    {0: -25.69393346270375, 5: -154.18974869023643, 6: -231.5293791760455, 7: 357.6391179106141, 8:
     93.40532418362432, 9: -37.45832313645163, 10: 104.0996495089623, 11: 29.8402934266605, 12:
     -43.53345659001114, 13: 96.32455395918828, 14: -39.17726167561544, 15: -149.72683625798564},
)
_B = (
    0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
    0.3111643669578199, -0.1521609496625161, 0.20136540080403034, 0.04471061572777259
)
_C = (
    0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726,
    0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6, 0.8571428571428571, 1.0
)
_C_EXTRA = (
    0.1, 0.2, 0.7777777777777778
)
_E3 = (
    -0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
    -0.4226823213237919, -0.1521609496625161, 0.20136540080403034, 0.02265179219836082, 0.0
)
_E5 = (
    0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502, 1.6643771824549864,
    -0.35032884874997366, 0.3341791187130175, 0.08192320648511571, -0.022355307863886294, 0.0
)


def _matrix(rows, n_cols):
    out = np.zeros((len(rows), n_cols))
    for i, row in enumerate(rows):
        for j, v in row.items():
            out[i, j] = v
    return out


#: Stages of the 8th-order formula, its order and that of the error estimator (scipy's class attributes).
N_STAGES, ORDER, ERROR_ESTIMATOR_ORDER = 12, 8, 7
A = _matrix(_A_ROWS, N_STAGES)
A_EXTRA = _matrix(_A_EXTRA_ROWS, N_STAGES + 4)
D = _matrix(_D_ROWS, N_STAGES + 4)
B, C, C_EXTRA, E3, E5 = (np.array(v) for v in (_B, _C, _C_EXTRA, _E3, _E5))
for _a in (A, A_EXTRA, D, B, C, C_EXTRA, E3, E5):
    _a.flags.writeable = False

#: Exponent of the step-size factor, −1/(error estimator order + 1) (scipy: 7 + 1).
_EXPONENT = -1.0 / 8.0


def _linear_combination(coeffs, terms):
    parts = [f"{float(c)!r} * {x}" for c, x in zip(coeffs, terms) if c != 0.0]
    return " + ".join(parts) if parts else "0.0"


def _dop853_source(n):
    """Source of ``attempt`` (one trial step: new state, new derivative, the 5th- and 3rd-order
    error estimates and the 13 stages) and ``dense`` (the three extra stages and the dense
    coefficients F3..F6 = h D K) for an ``n``-component state held in scalars."""
    AX, CX, ns = A_EXTRA, C_EXTRA, N_STAGES
    ys = ", ".join(f"y{i}" for i in range(n))

    def k(s):
        return ", ".join(f"k{s}_{i}" for i in range(n))

    def combo(coeffs, i, upto):
        return _linear_combination(coeffs[:upto], [f"k{j}_{i}" for j in range(upto)])

    allk = ", ".join(k(s) for s in range(ns + 1))
    src = [f"def attempt(f, t, h, {ys}, {k(0)}):"]
    for s in range(1, ns):
        args = ", ".join(f"y{i} + h * ({combo(A[s], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(C[s])!r} * h, {args})")
    for i in range(n):
        src.append(f"    z{i} = y{i} + h * ({combo(B, i, ns)})")
    zs = ", ".join(f"z{i}" for i in range(n))
    src.append(f"    {k(ns)}, = f(t + h, {zs})")
    e5 = ", ".join(combo(E5, i, ns + 1) for i in range(n))
    e3 = ", ".join(combo(E3, i, ns + 1) for i in range(n))
    src.append(f"    return ({zs},), ({k(ns)},), ({e5},), ({e3},), ({allk},)")
    src.append(f"def dense(f, t, h, {ys}, stages):")
    src.append(f"    {allk}, = stages")
    for r in range(AX.shape[0]):
        s = ns + 1 + r
        args = ", ".join(f"y{i} + h * ({combo(AX[r], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(CX[r])!r} * h, {args})")
    rows = ", ".join(f"h * ({combo(D[r], i, D.shape[1])})" for r in range(D.shape[0]) for i in range(n))
    src.append(f"    return ({rows},)")
    return "\n".join(src) + "\n"


_DOP853_KERNELS = {}


def _dop853_kernels(n):
    if n not in _DOP853_KERNELS:
        namespace = {}
        exec(compile(_dop853_source(n), f"<DOP853 scalar kernels, n = {n}>", "exec"), namespace)
        _DOP853_KERNELS[n] = (namespace["attempt"], namespace["dense"])
    return _DOP853_KERNELS[n]


def _initial_step(f, t, y, fy, t_end, rtol, atol):
    """First step size: Hairer, Nørsett & Wanner II.4, as scipy's ``select_initial_step`` (order 7).
    Costs one RHS evaluation."""
    n = len(y)
    sc = [atol + abs(v) * rtol for v in y]
    d0 = math.sqrt(sum((v / s) ** 2 for v, s in zip(y, sc)) / n)
    d1 = math.sqrt(sum((v / s) ** 2 for v, s in zip(fy, sc)) / n)
    h0 = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, t_end - t)
    f1 = f(t + h0, *[v + h0 * w for v, w in zip(y, fy)])
    d2 = math.sqrt(sum(((a - b) / s) ** 2 for a, b, s in zip(f1, fy, sc)) / n) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / 8)
    return min(100 * h0, h1, t_end - t)


def _error_norm(y, z, e5, e3, h_abs, rtol, atol):
    """scipy's DOP853 error norm of one trial step (both embedded estimates, scaled by the larger
    of the old and new state)."""
    n5 = n3 = 0.0
    for a, b, e, g in zip(y, z, e5, e3):
        s = atol + max(abs(a), abs(b)) * rtol
        n5 += (e / s) ** 2
        n3 += (g / s) ** 2
    return 0.0 if n5 == 0.0 and n3 == 0.0 else h_abs * n5 / math.sqrt((n5 + 0.01 * n3) * len(y))


def _accepted_step(attempt, f, t, y, fy, h_abs, t_end, rtol, atol):
    """Try steps from ``t`` until one passes the error test (scipy's step-size control).

    Returns
    -------
    tuple
        (t_new, h, z, fz, stages, next h_abs, RHS evaluations, rejected attempts).
    """
    min_step = 10 * abs(math.nextafter(t, math.inf) - t)
    h_abs = max(h_abs, min_step)
    rejected = False
    nfev = nrej = 0
    while True:
        if h_abs < min_step:
            raise IntegrationError(f"DOP853 failed at t = {t:.6g} s: required step size is less than "
                                   f"spacing between numbers")
        t_new = min(t + h_abs, t_end)
        h = t_new - t
        h_abs = abs(h)
        z, fz, e5, e3, stages = attempt(f, t, h, *y, *fy)
        nfev += 12
        err = _error_norm(y, z, e5, e3, h_abs, rtol, atol)
        if err < 1.0:
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** _EXPONENT)
            h_abs *= min(1.0, fac) if rejected else fac
            return t_new, h, z, fz, stages, h_abs, nfev, nrej
        h_abs *= max(0.2, 0.9 * err ** _EXPONENT)   # also for a NaN error: the step shrinks
        rejected = True
        nrej += 1


def _dense_samples(t_eval, t_old, t_new_all, h_all, y_old, coef, n):
    """Dense output at every sample time at once (scipy's ``Dop853DenseOutput``, vectorised);
    shape (len(t_eval), n)."""
    idx = np.minimum(np.searchsorted(np.array(t_new_all), t_eval, side="left"), len(t_old) - 1)
    x = ((t_eval - np.array(t_old)[idx]) / np.array(h_all)[idx])[:, None]
    F = np.array(coef).reshape(len(coef), 7, n)[idx]
    out = np.zeros((t_eval.size, n))
    for i in range(6, -1, -1):
        out += F[:, i]
        out *= x if i % 2 == 0 else 1.0 - x
    out += np.array(y_old)[idx]
    return out


class ScalarDOP853(Solver):
    """DOP853 on a small state held in Python floats, resumable block by block (a
    :class:`~gyro_instrument.core.solver.Solver`).

    ``f(t, *y) -> tuple`` of the derivatives. Same method, step control and dense output as
    ``integrate(..., method="DOP853")`` (see the module docstring). :meth:`advance` steps until the
    block's last sample is reached, evaluates the block from the steps taken for it and keeps only
    the last step (the next block's first samples may lie in it), so the steps are those of one run
    from ``t0`` to ``t_end`` and every sample is evaluated from the same step as in one call over the
    whole run: the blocks concatenate bit for bit (``tests/test_streaming.py``), in memory of one
    block. ``nfev`` counts every RHS evaluation as ``integrate`` does (15 per accepted step, 12 per
    rejected, 2 at the start).

    Raises
    ------
    IntegrationError
        A non-finite initial state; from :meth:`advance`, a step size below the spacing of floats
        or a non-finite state.
    """

    method = "DOP853"

    def __init__(self, f, y0, t0, t_end, rtol=1e-10, atol=1e-12) -> None:
        super().__init__(t0, t_end)
        y = tuple(float(v) for v in y0)
        if not all(math.isfinite(v) for v in y):
            raise IntegrationError(f"initial state is not finite: {y}")
        self.f, self.y, self.n = f, y, len(y)
        self.rtol = max(float(rtol), 100 * np.finfo(float).eps)   # as scipy's validate_tol
        self.atol = float(atol)
        self._nfev = self.nsteps = self.nrej = 0
        self._steps = ([], [], [], [], [])      # t_old, t_new, h, y_old, dense coefficients
        if self.t_end != self.t0:
            with self.clock():
                self.attempt, self.dense = _dop853_kernels(self.n)
                self.fy = tuple(f(self.t, *y))
                self.h_abs = _initial_step(f, self.t, y, self.fy, self.t_end, self.rtol, self.atol)
                self._nfev = 2

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""
        return self._nfev

    def _step_impl(self):
        """One accepted step from the current state; its dense coefficients are kept."""
        f, t, y, fy = self.f, self.t, self.y, self.fy
        t_new, h, z, fz, stages, self.h_abs, evals, rejections = _accepted_step(
            self.attempt, f, t, y, fy, self.h_abs, self.t_end, self.rtol, self.atol)
        dy = [b - a for a, b in zip(y, z)]
        t_old, t_new_all, h_all, y_old, coef = self._steps
        coef.append((*dy, *[h * a - d for a, d in zip(fy, dy)],
                     *[2 * d - h * (a + b) for a, b, d in zip(fy, fz, dy)], *self.dense(f, t, h, *y, stages)))
        t_old.append(t)
        t_new_all.append(t_new)
        h_all.append(h)
        y_old.append(y)
        self._nfev += evals + 3
        self.nrej += rejections
        self.nsteps += 1
        self.t_old, self.t, self.y, self.fy = t, t_new, z, fz

    def _dense_output_impl(self):
        """The last step's 7th-order interpolant (scipy's ``Dop853DenseOutput``)."""
        last = tuple(kept[-1:] for kept in self._steps)
        n = self.n

        def sol(t):
            return _dense_samples(np.atleast_1d(np.asarray(t, dtype=float)), *last, n).T
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """States at the sample times ``t`` (1-D, non-decreasing, not before the previous block's
        last sample nor past ``t_end``), s. Returns a :class:`Trajectory` of this block whose
        ``nfev``, ``wall_time_s`` and ``cpu_time_s`` count the whole run so far; ``progress(t)``
        after each step."""
        t = np.asarray(t, dtype=float)
        if self.t_end == self.t0:
            return Trajectory(t, np.array(self.y)[:, None].repeat(t.size, axis=1), 0, 0.0, 0.0, "DOP853")
        if t.size and t[-1] > self.t_end:
            raise IntegrationError(f"sample time {t[-1]!r} s is after the run's end {self.t_end!r} s")
        with self.clock():
            last = float(t[-1]) if t.size else self.t
            while self.t < last or not self._steps[0]:
                self.take_step()
                if progress is not None:
                    progress(self.t)
            out = _dense_samples(t, *self._steps, self.n) if t.size else np.empty((0, self.n))
            for kept in self._steps:               # the last step may hold the next block's first samples
                del kept[:-1]
        self.meta = {"rtol": self.rtol, "atol": self.atol, "nsteps": self.nsteps, "nrejected": self.nrej,
                     "driver": "scalar"}
        return self.trajectory(t, out.T.copy())


def integrate_dop853_scalar(f, y0, t_eval, rtol=1e-10, atol=1e-12) -> Trajectory:
    """DOP853 on a small state held in Python floats over ``t_eval`` at once: one
    :meth:`ScalarDOP853.advance` from ``t_eval[0]`` to ``t_eval[-1]`` (``t_eval`` non-decreasing)."""
    t_eval = np.asarray(t_eval, dtype=float)
    return ScalarDOP853(f, y0, t_eval[0], t_eval[-1], rtol=rtol, atol=atol).advance(t_eval)


def first_crossing(f, y0, t_end, g, after=0.0, rtol=1e-10, atol=1e-12) -> tuple:
    """Integrate ``f`` (as :class:`ScalarDOP853`) from ``y0`` at 0 until ``g(y)`` first crosses zero
    downward after ``after`` (an event of ``solve_ivp`` with direction −1 and a terminal stop; ``g``
    counts as positive up to ``after``), and locate the crossing on the dense output by bisection
    to adjacent doubles.

    Returns
    -------
    t_event : float or None
        Time of the crossing, s (None: no crossing up to ``t_end``).
    y_event : tuple or None
        The state there.
    sol : callable
        ``sol(t) -> array (n, len(t))``: the dense output at any times in [0, the last step's end].
    nfev : int
        Right-hand-side evaluations.
    """
    run = ScalarDOP853(f, y0, 0.0, t_end, rtol=rtol, atol=atol)
    n = run.n

    def sol(t):
        return _dense_samples(np.atleast_1d(np.asarray(t, dtype=float)), *run._steps, n).T

    def g_at(t):
        return g(tuple(sol(t)[:, 0])) if t > after else 1.0
    g_old = 1.0
    while run.t_end != run.t0 and run.t < run.t_end:
        t_old = run.t
        run.step()
        g_new = g(run.y) if run.t > after else 1.0
        if g_old >= 0.0 >= g_new:
            lo, hi = max(t_old, after), run.t
            if g_at(lo) <= 0.0:
                hi = lo
            while True:
                mid = 0.5 * (lo + hi)
                if not lo < mid < hi:
                    break
                if g_at(mid) > 0.0:
                    lo = mid
                else:
                    hi = mid
            y_hit = run.y if hi == run.t else tuple(sol(hi)[:, 0])
            return hi, y_hit, sol, run.nfev
        g_old = g_new
    return None, None, sol, run.nfev

