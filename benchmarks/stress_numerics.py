r"""Numerical corners of the angular-velocity integration (Boyle 2016, arXiv:1604.08139, Secs. II–V).

Every integration goes through :func:`run`, which calls ``pnrotor.integrate_angular_velocity`` and
counts a crash when it raises or returns non-finite rotors; a nonzero status is an outcome, reported
with its message.  Errors are δ of eq:error_norm against an exact rotor:

* the paper's precessing and nutating binary (eq:BinaryRotor, :mod:`pnrotor.analytic`);
* a fixed-axis ω(t) = f(t) ê, whose rotor is exactly R(t) = exp(½ F(t) ê) R₀ with F = ∫₀ᵗ f
  (eq:integrate-spinor with commuting ω's; :func:`axis_rotor`), for f zero, constant, cos t, a sign
  flip (a jump), a kink |t − t₀|, a Gaussian pulse of 10⁶ × the base rate, and a 10⁶ exponential ramp.

Cases (areas of the table):

a. *long runs*: the binary over 10⁴ orbits (T = 10⁷; --quick 10⁶) with the rotor (eq:integrate-spinor)
   and the generator (eq:log_deriv_omega with the reset eq:generator_reset), DOP853: the growth of
   max δ over [0, t] (log-log slope over t ∈ [T/100, T]), the drift of the unnormalized rotor's norm
   ||R| − 1| (``integrate_angular_velocity`` normalizes its output rotors; the raw state is read from
   the DOP853 dense output, which equals the accepted step's state at every step end), the number
   of generator resets.  At T = 10⁷ the paper's α̇ = 2α/10⁵ takes the opening angle α + α̇t to
   201 α = 78.9 rad: ω stays bounded (|ω| ≤ Ω_orb + |Ω_prec| + |α̇| + …), and every angle is
   reduced exactly (:func:`pnrotor.analytic.cos_sin`), so the binary stays a well-defined, exact test
   problem — but the orbital axis tumbles 12.6 times instead of precessing on a cone; the paper's
   parameters are kept.
b. *ω corners*: every formulation (rotor, generator, generator-noreset, vectors3, vectors2,
   vectors-damped; eq:integrate-spinor, eq:log_deriv_omega, eq:generator_reset,
   eq:integr-frame-vectors, eq:vector-norm-damping, eq:vector-orthogonality-damping) × both methods
   on each fixed-axis ω: δ, sign continuity (samples with R · R_exact < 0), nfev.  Bulirsch–Stoer may
   accept a step straddling a jump or a kink with an error the tolerance does not control: when the
   jump lies within the first or last substep H/n of every column, no evaluation of Gragg's rule
   sees it, and the extrapolated columns agree on the wrong answer.
c. *branches*: the generator started exactly at and near |r| = π/2; the unreset generator through
   |r| = π (R → −1) with ω ∥ r (where eq:log_deriv_omega's θ cot θ → ∞ cancels analytically) and
   with R₀ tilted off the axis (a near-singular passage); the reset generator when Bulirsch–Stoer
   steps cross |r| = π on the binary; the rotor through −1; quaternion exp/log round trips next to
   the branch point (angles near 2π, both signs).
d. *backward*: the binary over [0, T] (T = 10⁶; --quick 10⁵) forward and back to t = 0, against R₀,
   every formulation × method, and backward from the exact R(T) against the exact rotor.

``cases(quick=False)`` yields one row per case (keys: area, case, tried, crashes, outcome,
worst_error, growth) for benchmarks/stress.py, which prints the table:

    python benchmarks/stress.py --only numerics [--quick]
"""

import math

import numpy as np
from numba import njit

from pnrotor import formulations as F
from pnrotor import integrate_angular_velocity
from pnrotor import quaternion as quat
from pnrotor.analytic import PrecessingNutatingBinary
from pnrotor.ode import RHS_SIG, dop853
from pnrotor.ode.result import STATUS_MESSAGES

FORMS = tuple(F.FORMULATIONS)
METHODS = ("DOP853", "Bulirsch-Stoer")
AXIS = np.array([1.0, 2.0, 2.0]) / 3.0
R0_GENERIC = quat.normalize(np.array([0.8, -0.3, 0.4, 0.2]))

# --------------------------------------------------------------------------------------------------
# fixed-axis angular velocities ω(t) = f(t) ê with their exact rotors
# --------------------------------------------------------------------------------------------------

# p = [kind, w0, w1, t0, s, A, ê (3)]
ZERO, CONSTANT, COSINE, JUMP, KINK, PULSE, RAMP = range(7)


@njit(cache=True)
def rate(t, p):
    """f(t) of the fixed-axis ω of kind p[0] (see :class:`AxisOmega`)."""
    kind, w0, w1, t0, s, A = int(p[0]), p[1], p[2], p[3], p[4], p[5]
    if kind == ZERO:
        return 0.0
    if kind == CONSTANT:
        return w0
    if kind == COSINE:
        return w0 * math.cos(t)
    if kind == JUMP:
        return w0 if t < t0 else w1
    if kind == KINK:
        return w0 * abs(t - t0)
    if kind == PULSE:
        x = (t - t0) / s
        return w0 * (1.0 + A * math.exp(-x * x))
    return w0 * math.exp(s * t)


@njit(cache=True)
def angle(t, p):
    """F(t) = ∫₀ᵗ f, exactly (the rotation angle about ê since t = 0)."""
    kind, w0, w1, t0, s, A = int(p[0]), p[1], p[2], p[3], p[4], p[5]
    if kind == ZERO:
        return 0.0
    if kind == CONSTANT:
        return w0 * t
    if kind == COSINE:
        return w0 * math.sin(t)
    if kind == JUMP:
        return w0 * t if t < t0 else w0 * t0 + w1 * (t - t0)
    if kind == KINK:
        return 0.5 * w0 * ((t - t0) * abs(t - t0) + t0 * abs(t0))
    if kind == PULSE:
        return w0 * (t + 0.5 * A * s * math.sqrt(math.pi) * (math.erf((t - t0) / s) + math.erf(t0 / s)))
    return w0 * math.expm1(s * t) / s


@njit(cache=True)
def axis_omega(t, p):
    f = rate(t, p)
    return (f * p[6], f * p[7], f * p[8])


@njit(RHS_SIG, cache=True)
def _rhs_rotor(t, y, p, dydt):
    F.rotor_derivative(axis_omega(t, p), y, p, dydt)


@njit(RHS_SIG, cache=True)
def _rhs_generator(t, y, p, dydt):
    F.generator_derivative(axis_omega(t, p), y, p, dydt)


@njit(RHS_SIG, cache=True)
def _rhs_vectors(t, y, p, dydt):
    F.vectors_derivative(axis_omega(t, p), y, p, dydt)


@njit(RHS_SIG, cache=True)
def _rhs_damped_vectors(t, y, p, dydt):
    F.damped_vectors_derivative(axis_omega(t, p), y, p, dydt)


_RHS = {F.rotor_derivative: _rhs_rotor, F.generator_derivative: _rhs_generator,
        F.vectors_derivative: _rhs_vectors, F.damped_vectors_derivative: _rhs_damped_vectors}


def axis_rotor(F_t, axis, R0):
    """The exact rotor exp(½ F ê) R₀ of a rotation by the angles F (N,) about the fixed unit axis ê."""
    return quat.multiply(quat.exp(0.5 * np.asarray(F_t, dtype=np.float64)[:, None] * axis), R0)


class AxisOmega:
    """ω(t) = f(t) ê about a fixed unit axis ê, with cached right-hand sides (the protocol of
    :class:`pnrotor.analytic.PrecessingNutatingBinary`, so nothing is compiled per process) and the
    exact rotor R(t) = exp(½ F(t) ê) R₀.

    kind: ZERO; CONSTANT f = w0; COSINE f = w0 cos t; JUMP f = w0 before t0, w1 after; KINK
    f = w0 |t − t0|; PULSE f = w0 (1 + A exp(−((t − t0)/s)²)); RAMP f = w0 exp(s t).
    """

    def __init__(self, kind, w0=1.0, w1=0.0, t0=0.0, s=1.0, A=0.0, axis=AXIS):
        self.params = np.array([kind, w0, w1, t0, s, A, *axis], dtype=np.float64)
        self.axis = self.params[6:9].copy()

    def integrand(self, formulation):
        return _RHS[formulation.derivative], self.params

    def angular_velocity(self, ts):
        return np.array([rate(t, self.params) for t in np.atleast_1d(ts)])[:, None] * self.axis

    def angle(self, ts):
        return np.array([angle(t, self.params) for t in np.atleast_1d(ts)])

    def rotor(self, ts, R0):
        return axis_rotor(self.angle(ts), self.axis, R0)

    def describe(self):
        return {"omega": "AxisOmega", "axis_omega_params": self.params.copy()}


# --------------------------------------------------------------------------------------------------
# running and summarizing
# --------------------------------------------------------------------------------------------------


def run(omega, t_span, R0, formulation, method, atol, exact=None, **kw):
    """One integration → dict: ``h`` (the FrameHistory or None), ``crash``, ``outcome`` (status message
    or exception), and with ``exact(t)`` (exact rotors at times t): ``delta`` (max δ, eq:error_norm)
    and ``flips`` (samples with R · R_exact < 0: sign discontinuities)."""
    try:
        h = integrate_angular_velocity(omega, t_span, R0, formulation, method, atol=atol, **kw)
    except Exception as exc:  # noqa: BLE001 — any exception on valid input is what this module counts
        return dict(h=None, crash=True, outcome=f"{type(exc).__name__}: {exc}", delta=math.inf, flips=0)
    finite = bool(np.all(np.isfinite(h.R)) and np.all(np.isfinite(h.t)))
    out = dict(h=h, crash=not finite, outcome=STATUS_MESSAGES.get(h.status, h.message) if finite else "non-finite",
               delta=None, flips=0)
    if exact is not None and finite:
        Re = exact(h.t)
        out["delta"] = float(np.max(quat.frame_error(h.R, Re)))
        out["flips"] = int(np.sum(np.einsum("ij,ij->i", h.R, Re) < 0.0))
    return out


def short(formulation):
    return {"generator-noreset": "noreset", "vectors-damped": "damped"}.get(formulation, formulation)


def status_text(runs):
    """'all reached t_end' or the distinct outcomes (status messages, exceptions) with counts, naming
    the runs (their ``label``) that did not reach t_end."""
    outcomes = {}
    for r in runs:
        outcomes.setdefault(r["outcome"].rstrip("."), []).append(r.get("label"))
    done = STATUS_MESSAGES[0].rstrip(".")
    if list(outcomes) == [done]:
        return "all reached t_end"
    return "; ".join(f"{len(labels)}× {o}" + ("" if o == done or None in labels else f" ({', '.join(labels)})")
                     for o, labels in outcomes.items())


def row(area, case, runs, outcome, worst=None, growth="—"):
    deltas = [r["delta"] for r in runs if r.get("delta") is not None]
    if worst is None and deltas:
        worst = max(deltas)
    return dict(area=area, case=case, tried=len(runs), crashes=sum(r["crash"] for r in runs),
                outcome=outcome, worst_error=None if worst is None else float(worst), growth=growth)


def slope(t, y, T):
    """Log-log slope of the running maximum of y(t) over 40 times log-spaced in [T/100, T]."""
    m = np.maximum.accumulate(np.abs(y))
    ts = np.geomspace(T / 100, T, 40)
    i = np.minimum(np.searchsorted(t, ts), len(t) - 1)
    return float(np.polyfit(np.log(t[i]), np.log(m[i]), 1)[0])


# --------------------------------------------------------------------------------------------------
# a. long runs of the analytic binary
# --------------------------------------------------------------------------------------------------


def long_run_cases(quick):
    T = 1e6 if quick else 1e7
    b = PrecessingNutatingBinary(T=T)
    R0 = b.rotor(0.0)
    beta = b.alpha + b.alpha_dot * T
    for formulation in ("rotor", "generator"):
        runs, notes, growth = [], [], []
        for atol in (1e-12, 1e-10):
            r = run(b, (0.0, T), R0, formulation, "DOP853", atol, exact=b.rotor, dense=formulation == "rotor")
            runs.append(r)
            h = r["h"]
            if r["crash"] or h.status != 0:
                notes.append(f"atol {atol:g}: {r['outcome']}")
                continue
            delta = b.frame_error(h.t, h.R)
            growth.append(f"δ ∝ t^{slope(h.t, delta, T):.2f} (atol {atol:g})")
            note = f"atol {atol:g}: {h.naccepted} steps, max δ {r['delta']:.2e}"
            if formulation == "rotor":
                drift = np.linalg.norm(h.dense(h.t), axis=1) - 1.0
                note += (f", max ||R|−1| {np.max(np.abs(drift)):.1e} (final {drift[-1]:+.1e}, "
                         f"∝ t^{slope(h.t, drift, T):.2f})")
            else:
                note += f", {h.n_resets} resets"
            notes.append(note)
        yield row("a. long run", f"binary, {formulation}, DOP853, T = {T:.0e} ({T / 1e3:.0f} orbits; "
                  f"α + α̇T = {beta:.1f} rad)", runs, "; ".join(notes), growth="; ".join(growth))


# --------------------------------------------------------------------------------------------------
# b. fixed-axis ω corners, every formulation × method
# --------------------------------------------------------------------------------------------------

T_AXIS = 20.0
T_KINK = 10.3  # inside the span, not on any step boundary by construction
AXIS_CASES = (
    ("ω = 0", AxisOmega(ZERO)),
    ("ω = ê constant (R passes −1 at t = 2π)", AxisOmega(CONSTANT)),
    ("ω = 3 cos t ê (reverses sign)", AxisOmega(COSINE, w0=3.0)),
    ("ω = +ê → −ê at t = 10.3 (sign flip, a jump)", AxisOmega(JUMP, w0=1.0, w1=-1.0, t0=T_KINK)),
    ("ω = |t − 10.3| ê (kink)", AxisOmega(KINK, t0=T_KINK)),
    ("ω = (1 + 10⁶ e^{−((t−10.3)/0.01)²}) ê (10⁶ pulse, ∫ = 1.8e4 rad)",
     AxisOmega(PULSE, t0=T_KINK, s=0.01, A=1e6)),
    ("ω = 10⁻³ e^{t ln(10⁶)/20} ê (10⁶ ramp)", AxisOmega(RAMP, w0=1e-3, s=math.log(1e6) / T_AXIS)),
)
ATOL_AXIS = 1e-10


def matrix(omega, t_span, R0, atol, exact, **kw):
    """One run per formulation × method → (runs, per-run labels)."""
    runs = []
    for formulation in FORMS:
        for method in METHODS:
            r = run(omega, t_span, R0, formulation, method, atol, exact=exact, **kw)
            r["label"] = f"{short(formulation)}/{'BS' if method != 'DOP853' else 'DOP'}"
            runs.append(r)
    return runs


def matrix_outcome(runs):
    """Statuses, max δ per formulation as DOP853/Bulirsch–Stoer (a run that stopped early counts up to
    where it stopped), sign flips, nfev range."""
    worst = {}
    for r in runs:
        name, method = r["label"].split("/")
        worst.setdefault(name, {})[method] = math.inf if r["delta"] is None else r["delta"]
    nfev = [r["h"].nfev for r in runs if r["h"] is not None]
    flips = [r["label"] for r in runs if r["flips"]]
    text = (f"{status_text(runs)}; max δ DOP/BS: "
            + ", ".join(f"{k} {v['DOP']:.0e}/{v['BS']:.0e}" for k, v in worst.items())
            + f"; nfev {min(nfev)}–{max(nfev)}")
    return text + (f"; sign flips in {', '.join(flips)}" if flips else "; signs continuous")


def axis_cases(quick):
    for label, omega in AXIS_CASES:
        runs = matrix(omega, (0.0, T_AXIS), R0_GENERIC, ATOL_AXIS, lambda t, w=omega: w.rotor(t, R0_GENERIC))
        yield row("b. ω corners", f"{label}, atol {ATOL_AXIS:g}, 6 formulations × 2 methods", runs,
                  matrix_outcome(runs))


# --------------------------------------------------------------------------------------------------
# c. branches: generator at |r| = π/2 and π, rotor through −1, exp/log round trips
# --------------------------------------------------------------------------------------------------

T_HALF_PI = 10 * math.pi + 1.0  # 5 turns and a bit: the last crossing is not at t_end
AXIS_60 = 0.5 * AXIS + 0.5 * math.sqrt(3.0) * np.array([2.0, 1.0, -2.0]) / 3.0  # 60° from AXIS


def sign_changes(omega, R0, T):
    """Sign changes of the scalar part of the exact (continuous) rotor over [0, T] on a fine grid, starting
    from the representative with scalar part ≥ 0: the generator's resets (one each time |r| reaches
    π/2), as long as no step spans two of them."""
    w = omega.rotor(np.linspace(0.0, T, 20001), R0)[:, 0]
    s = np.where(w >= 0.0, 1, -1)
    return int(np.sum(s[1:] != s[:-1]))


def generator_half_pi_runs(offsets=(0.0, 1e-12, 1e-6), methods=METHODS):
    """The generator from R₀ = exp(θ₀ ê), θ₀ = π/2 − offset (offset 0: R₀ = (0, ê), whose generator has
    |r| = atan2(1, 0) = π/2 exactly), with ω = ±ê' at 60° to ê over [0, 10π + 1] → runs with
    ``resets`` and ``expected`` (:func:`sign_changes`) set."""
    runs = []
    for offset in offsets:
        th0 = 0.5 * math.pi - offset
        R0 = np.array([math.cos(th0) if offset else 0.0, *(math.sin(th0) * AXIS)])
        for sign in (1.0, -1.0):
            omega = AxisOmega(CONSTANT, w0=sign, axis=AXIS_60)
            for method in methods:
                r = run(omega, (0.0, T_HALF_PI), R0, "generator", method, ATOL_AXIS,
                        exact=lambda t, w=omega, R0=R0: w.rotor(t, R0))
                r["resets"] = None if r["h"] is None else r["h"].n_resets
                r["expected"] = sign_changes(omega, R0, T_HALF_PI)
                runs.append(r)
    return runs


def parallel_reset_probe():
    """The generator from |r| = π/2 with ω = ê ∥ r over [0, 10π + 1], DOP853 called directly to see the raw
    state: ṙ = ω/2 is constant, steps grow ×6 each, and a step spanning several half-turns is followed
    by one reset, which subtracts the nearest multiple of π → (resets, crossings of |r| = π/2, largest |r|
    after a reset, δ at the end, longest step)."""
    omega = AxisOmega(CONSTANT)
    R0 = np.array([0.0, *AXIS])
    form = F.get("generator")
    res = dop853(_rhs_generator, 0.0, form.initial_state(R0), T_HALF_PI, ATOL_AXIS, args=omega.params,
                 after_step=F.generator_reset)
    delta = float(quat.frame_error(quat.exp(res.y[-1]), omega.rotor(res.t[-1:], R0)[0]))
    return (res.n_modified, sign_changes(omega, R0, T_HALF_PI), float(np.max(np.linalg.norm(res.y, axis=1))),
            delta, float(np.max(np.diff(res.t))))


def generator_derivative_along_axis(distance):
    """(|ṙ − ½ω| for ω ∥ r, |ṙ| for ω ⊥ r) of eq:log_deriv_omega at |r| = π (1 − distance): along the
    axis the exact ṙ is ½ ω (θ cot θ cancels), across it ṙ diverges as 1/(π − θ)."""
    along, across = AXIS, np.array([2.0, 1.0, -2.0]) / 3.0
    r = math.pi * (1.0 - distance) * AXIS
    out = []
    for w in (along, across):
        d = np.empty(3)
        F.generator_derivative(w, r, np.empty(0), d)
        out.append(d)
    return float(np.max(np.abs(out[0] - 0.5 * along))), float(np.linalg.norm(out[1]))


def through_minus_one(tilt):
    """R₀ = 1 tilted by ``tilt`` rad about ŷ, ω = ê: R(t) = exp(t ê/2) R₀ passes −1 (tilt 0) or within
    ~tilt of it at t = 2π, and again… over [0, 4π + 1]; every formulation × method."""
    R0 = np.array([math.cos(0.5 * tilt), 0.0, math.sin(0.5 * tilt), 0.0])
    omega = AxisOmega(CONSTANT)
    return matrix(omega, (0.0, T_MINUS_ONE), R0, ATOL_AXIS, lambda t: omega.rotor(t, R0))


T_MINUS_ONE = 4 * math.pi + 1.0


def round_trips(n_axes):
    """Quaternion exp/log next to the branch point R = −1: for unit rotors q = ±exp(½θ ê) with θ = 2π ± ε
    (ε = 10⁻¹ … 10⁻¹⁵, 0) about ``n_axes`` random axes, max |exp(log q) − q| and max δ(exp(log q), q); for
    generators r = (π − d) ê (d = 10⁻¹ … 10⁻¹⁴), max |log(exp r) − r|."""
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(n_axes, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    eps = np.array([0.0, *10.0 ** -np.arange(1, 16)])
    theta = np.concatenate([2 * math.pi - eps, 2 * math.pi + eps[1:]])
    # |r| within rounding of π (k = 15) is the generator of −1 up to 1e-16, whose sign is arbitrary
    d = 10.0 ** -np.arange(1, 15)
    r = 0.5 * theta[:, None, None] * axes[None, :, :]
    q = quat.exp(r).reshape(-1, 4)
    q = np.concatenate([q, -q])
    back = quat.exp(quat.log(q))
    gen = (math.pi - d)[:, None, None] * axes[None, :, :]
    return (float(np.max(np.abs(back - q))), float(np.max(quat.frame_error(back, q))),
            float(np.max(np.abs(quat.log(quat.exp(gen)) - gen))), len(q) + gen.size // 3)


def branch_cases(quick):
    runs = generator_half_pi_runs()
    right = sum(r["resets"] == r["expected"] for r in runs)
    yield row("c. branches", "generator from |r| = π/2 exactly, π/2 − 1e-12, π/2 − 1e-6; ω = ±ê' at 60° to r "
              f"over [0, 10π + 1]; atol {ATOL_AXIS:g}; both methods", runs,
              f"{status_text(runs)}; resets = sign changes of the exact scalar part in {right}/{len(runs)} "
              f"({'/'.join(sorted({str(r['resets']) for r in runs}))}); sign flips {sum(r['flips'] for r in runs)}")
    resets, crossings, r_max, delta, h_max = parallel_reset_probe()
    yield dict(area="c. branches", case="generator from |r| = π/2 with ω = ê ∥ r over [0, 10π + 1] (ṙ = ω/2: "
               f"exactly linear, the last step is {h_max:.1f} long), DOP853 on the raw state", tried=1, crashes=0,
               outcome=f"{resets} resets for {crossings} crossings of |r| = π/2 (one per step, of the nearest "
               f"multiple of π): |r| ≤ {r_max:.4f} after every step; δ at t_end {delta:.1e}",
               worst_error=delta, growth="—")
    distances = (0.0, 1e-15, 1e-12, 1e-8, 1e-4)
    probes = [generator_derivative_along_axis(d) for d in distances]
    yield dict(area="c. branches", case="generator ṙ (eq:log_deriv_omega) at |r| = π(1 − d), "
               "d = " + ", ".join(f"{d:g}" for d in distances), tried=len(distances), crashes=0,
               outcome="ω ∥ r: |ṙ − ½ω| = " + ", ".join(f"{a:.1e}" for a, _ in probes)
               + "; ω ⊥ r: |ṙ| = " + ", ".join(f"{b:.1e}" for _, b in probes),
               worst_error=max(a for a, _ in probes), growth="∥: ∝ 1/d (cancellation); ⊥: ∝ 1/d (singular)")
    for tilt in (0.0, 1e-12, 1e-8):
        runs = through_minus_one(tilt)
        where = "through −1 (generator-noreset: |r| = π, ω ∥ r)" if tilt == 0 else f"{tilt:g} rad from −1"
        yield row("c. branches", f"R = exp(tê/2) R₀ {where}, R₀ = exp({tilt:g} ŷ/2), t ∈ [0, 4π + 1]; "
                  f"atol {ATOL_AXIS:g}, 6 formulations × 2 methods", runs, matrix_outcome(runs))
    a, d, g, n = round_trips(20 if quick else 200)
    yield dict(area="c. branches", case="exp(log q) for q = ±exp(½θ ê), θ = 2π ± 10⁻ᵏ (k = 1..15, and 2π); "
               "log(exp r) for |r| = π − 10⁻ᵏ (k = 1..14); random axes", tried=n, crashes=0,
               outcome=f"max |exp(log q) − q| {a:.1e}, max δ {d:.1e}; max |log(exp r) − r| {g:.1e}",
               worst_error=max(a, d, g), growth="—")


# --------------------------------------------------------------------------------------------------
# d. backward integration
# --------------------------------------------------------------------------------------------------


def backward_cases(quick):
    T = 1e5 if quick else 1e6
    b = PrecessingNutatingBinary(T=T)
    R0 = b.rotor(0.0)
    for formulation in FORMS:
        runs, notes = [], []
        for method in METHODS:
            fwd = run(b, (0.0, T), R0, formulation, method, 1e-12, exact=b.rotor)
            exact_back = run(b, (T, 0.0), b.rotor(T), formulation, method, 1e-12, exact=b.rotor)
            runs += [fwd, exact_back]
            name = "DOP" if method == "DOP853" else "BS"
            if fwd["crash"] or fwd["h"].status != 0:
                notes.append(f"{name}: forward {fwd['outcome'].rstrip('.')} at t = {fwd['h'].t[-1]:.2g}" if fwd["h"]
                             else f"{name}: forward {fwd['outcome']}")
                continue
            back = run(b, (T, 0.0), fwd["h"].R[-1], formulation, method, 1e-12)
            runs.append(back)
            if back["crash"] or back["h"].status != 0:
                notes.append(f"{name}: back {back['outcome']}")
                continue
            back["delta"] = float(quat.frame_error(back["h"].R[-1], R0))
            notes.append(f"{name}: δ(R_back(0), R₀) {back['delta']:.1e} / fwd max δ {fwd['delta']:.1e} = "
                         f"{back['delta'] / fwd['delta']:.2f}; from exact R(T) max δ {exact_back['delta']:.1e}")
        yield row("d. backward", f"binary, {formulation}, [0, {T:.0e}] forward then back, and back from exact "
                  "R(T); atol 1e-12", runs, f"{status_text(runs)}; " + "; ".join(notes))


# --------------------------------------------------------------------------------------------------


def cases(quick=False):
    """Rows of the table (dicts: area, case, tried, crashes, outcome, worst_error, growth), computed
    lazily, case by case."""
    yield from long_run_cases(quick)
    yield from axis_cases(quick)
    yield from branch_cases(quick)
    yield from backward_cases(quick)

