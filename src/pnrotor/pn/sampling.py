r"""Last stage of a PN run: the output history from the integrated halves, at the times the user asked for.

:func:`sample` returns t and the arrays (v, Φ, χ₁, χ₂, R, ℓ̂) of an :class:`~pnrotor.pn.evolve.Evolution`
from the forward (and backward) :class:`~pnrotor.ode.OdeResult`:

* ``'steps'`` / ``'final'``: the integrator's accepted steps (both halves, in time order) or the last one;
* ``'dt'``: t = kΔt (t = 0 at f_ref, as LALSuite's grid from fStart) within the integrated span;
* ``'per_orbit'``: the times where Φ = 2πj/n (Newton on each step's interpolant, :func:`_phase_roots`).

Before anything is allocated, the number of samples Δt or n per orbit implies is checked against the
memory available (:func:`_check_memory`): a ValueError naming ``sampling`` and the size, not a
MemoryError after the run.

Uniform and per-orbit samples come from DOP853's 7th-order dense output (Hairer's ``contd8``), never by
shortening steps.  The rotor is rebuilt from the state and normalized only here (Boyle 2016,
arXiv:1604.08139: R stays unnormalized inside the integration): aligned runs R = R₀ exp(Φẑ/2), the
co-precessing state R = R_p exp(Φẑ/2), the orbital state R itself; ℓ̂ = R ẑ R⁻¹.  The kernels are numba,
one pass over the rows in blocks of 64 samples (buffers allocated once per call, none per sample).
"""

import math

import numpy as np
from numba import njit

from pnrotor import processes

from . import layout

MODE_ALIGNED, MODE_COPRECESSING, MODE_ORBITAL = 0, 1, 2
"""How a state row becomes a history row: see :func:`_store_block`."""


def output_mode(use_aligned, rotor):
    """The :func:`fill_history` mode of a run's state: its Settings' ``use_aligned`` and ``rotor``."""
    if use_aligned:
        return MODE_ALIGNED
    return MODE_ORBITAL if rotor == "orbital" else MODE_COPRECESSING


_BLOCK = 64
"""Samples per block of :func:`fill_history`: its buffers stay in L1."""


@njit(cache=True, inline="always")
def _contd8(coef, j, i, theta, th1):
    """Component i of the DOP853 dense output of segment j at θ (th1 = 1 − θ): the same polynomial as
    :func:`pnrotor.ode.result.contd8` (Hairer's ``contd8``, r₁ + θ(r₂ + θ'(r₃ + θ(r₄ + θ'(r₅ + θ(r₆ +
    θ'(r₇ + θ r₈))))))), θ' = 1 − θ), indexing coef[j] in place (slicing coef[j] per sample cost more than
    the polynomial for small states).  Checked against ``DenseOutput`` in the tests."""
    return coef[j, 0, i] + theta * (coef[j, 1, i] + th1 * (coef[j, 2, i] + theta * (coef[j, 3, i] + th1 * (
        coef[j, 4, i] + theta * (coef[j, 5, i] + th1 * (coef[j, 6, i] + theta * coef[j, 7, i]))))))


@njit(cache=True)
def _contd8_slope(coef, j, i, theta):
    """(value, d/dθ) of :func:`_contd8` at θ: its nested form differentiated level by level, inside out."""
    th1 = 1.0 - theta
    a = coef[j, 7, i]
    da = 0.0
    for k in range(6, -1, -1):   # a ← r_k + x a, x = θ for even k, θ' = 1 − θ for odd k (k from 0: r₁ is coef[j, 0])
        if k % 2 == 1:
            da = th1 * da - a
            a = coef[j, k, i] + th1 * a
        else:
            da = theta * da + a
            a = coef[j, k, i] + theta * a
    return a, da


@njit(cache=True, inline="always")
def _store_row(i, vv, ph, w, x, yy, z, v, Phi, R, ell):
    """Normalize R = (w, x, y, z) and store v, Φ, R and ℓ̂ = R ẑ R⁻¹ in row i (ℓ̂ only if ``ell`` has rows)."""
    inv = 1.0 / math.sqrt(w * w + x * x + yy * yy + z * z)
    w *= inv
    x *= inv
    yy *= inv
    z *= inv
    v[i] = vv
    Phi[i] = ph
    R[i, 0] = w
    R[i, 1] = x
    R[i, 2] = yy
    R[i, 3] = z
    if ell.shape[0]:
        ell[i, 0] = 2.0 * (x * z + w * yy)
        ell[i, 1] = 2.0 * (yy * z - w * x)
        ell[i, 2] = w * w - x * x - yy * yy + z * z


# fdlibm (Sun Microsystems, 1993; e_rem_pio2.c, k_sin.c, k_cos.c): π/2 in three parts of 33, 33 and 53 bits, and
# the minimax polynomials of sin and cos on [−π/4, π/4]
_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1, _PIO2_2, _PIO2_2T = 1.57079632673412561417e+00, 6.07710050630396597660e-11, 2.02226624879595063154e-21
_S1, _S2, _S3, _S4, _S5, _S6 = (-1.66666666666666324348e-01, 8.33333333332248946124e-03,
                                -1.98412698298579493134e-04, 2.75573137070700676789e-06,
                                -2.50507602534068634195e-08, 1.58969099521155010221e-10)
_C1, _C2, _C3, _C4, _C5, _C6 = (4.16666666666666019037e-02, -1.38888888888741095749e-03,
                                2.48015872894767294178e-05, -2.75573143513906633035e-07,
                                2.08757232129817482790e-09, -1.13596475577881948265e-11)
_COS_QUADRANT = np.array([1.0, 0.0, -1.0, 0.0])
_SIN_QUADRANT = np.array([0.0, 1.0, 0.0, -1.0])
_REDUCTION_LIMIT = 2.0 ** 19 * _PIO2_1
"""Below it n = round(x 2/π) < 2¹⁹, so n times the 33-bit parts of π/2 is exact and x − n π/2 is found to
about an ulp of itself."""


@njit(cache=True, fastmath={'contract'})
def _half_angle_cos_sin(ph, cs, m):
    """cs[0, b], cs[1, b] = cos(ph[b]/2), sin(ph[b]/2) for b < m, within 1.2e-16 of the exact values (tests;
    libm's are within 5.6e-17).

    x = ph/2 is reduced to r = x − n π/2, |r| ≤ π/4, with π/2 in three parts (Cody and Waite), and cos r, sin r
    are fdlibm's polynomials; the quadrant n mod 4 picks the signs and the swap by multiplying with 0 and ±1,
    which is exact.  With no call and no branch the loop is vectorized, which a call of
    libm's ``sincos`` prevents.  A block with some |x| beyond :data:`_REDUCTION_LIMIT` (Φ > 1.6e6 rad,
    ~260,000 orbits) takes libm's."""
    far = False
    for b in range(m):
        far |= not abs(0.5 * ph[b]) < _REDUCTION_LIMIT
    if far:
        for b in range(m):
            cs[0, b] = math.cos(0.5 * ph[b])
            cs[1, b] = math.sin(0.5 * ph[b])
        return
    for b in range(m):
        x = 0.5 * ph[b]
        n = math.floor(x * _INVPIO2 + 0.5)
        r = ((x - n * _PIO2_1) - n * _PIO2_2) - n * _PIO2_2T
        z = r * r
        sin_r = r + z * r * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        hz = 0.5 * z
        w = 1.0 - hz
        cos_r = w + (((1.0 - w) - hz) + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6))))))
        q = int(n) & 3
        cs[0, b] = cos_r * _COS_QUADRANT[q] - sin_r * _SIN_QUADRANT[q]
        cs[1, b] = sin_r * _COS_QUADRANT[q] + cos_r * _SIN_QUADRANT[q]


@njit(cache=True)
def _store_block(mode, y, cs, m, i0, R0, ell0, c1, c2, v, Phi, chi1, chi2, R, ell):
    """History rows i0 … i0 + m − 1 from the states y[:, :m] (one column per row), cs a (2, _BLOCK) buffer.

    cos and sin of Φ/2 go first, in a loop of their own (:func:`_half_angle_cos_sin`), so that the loop writing
    the rows has no call and is vectorized.  Per mode:

    * aligned: y = [v, Φ], R = R₀ exp(Φẑ/2), spins and ℓ̂ constant (written only into χ₁, χ₂, ℓ̂ arrays with
      rows: :func:`allocate_history` gives an aligned run none);
    * coprecessing: y = [v, χ₁, χ₂, R_p, Φ], R = R_p exp(Φẑ/2);
    * orbital: y = [v, χ₁, χ₂, R, Φ];

    and for these two, χ₁, χ₂ and ℓ̂ arrays without rows get none (:func:`fill_history` then leaves the spins' rows of
    y unset).

    exp(Φẑ/2) = (cos Φ/2, 0, 0, sin Φ/2) and q·(c, 0, 0, s) = (wc − zs, xc + ys, yc − xs, zc + ws).
    """
    if mode != MODE_ORBITAL:
        _half_angle_cos_sin(y[1 if mode == MODE_ALIGNED else 11], cs, m)
    if mode == MODE_ALIGNED:
        # R₀ is a unit rotor and ℓ̂ = R₀ ẑ R₀⁻¹ is constant (rotations about ẑ fix it): ell0 = ℓ̂
        for b in range(m):
            i = i0 + b
            c = cs[0, b]
            s = cs[1, b]
            v[i] = y[0, b]
            Phi[i] = y[1, b]
            R[i, 0] = R0[0] * c - R0[3] * s
            R[i, 1] = R0[1] * c + R0[2] * s
            R[i, 2] = R0[2] * c - R0[1] * s
            R[i, 3] = R0[3] * c + R0[0] * s
        if chi1.shape[0] > 0:   # rows of their own (evolve_many's outputs); evolve's are views of one row
            for b in range(m):
                for k in range(3):
                    ell[i0 + b, k] = ell0[k]
                    chi1[i0 + b, k] = c1[k]
                    chi2[i0 + b, k] = c2[k]
    else:
        for b in range(m):
            i = i0 + b
            w, x, yy, z = y[7, b], y[8, b], y[9, b], y[10, b]
            if mode == MODE_COPRECESSING:
                c = cs[0, b]
                s = cs[1, b]
                w, x, yy, z = w * c - z * s, x * c + yy * s, yy * c - x * s, z * c + w * s
            _store_row(i, y[0, b], y[11, b], w, x, yy, z, v, Phi, R, ell)
            if chi1.shape[0]:
                for k in range(3):
                    chi1[i, k] = y[1 + k, b]
                    chi2[i, k] = y[4 + k, b]


@njit(cache=True)
def fill_history(mode, seg_t, seg_h, coef, tq, reverse, Y, R0, ell0, c1, c2, offset, v, Phi, chi1, chi2, R,
                  ell):
    """History rows offset, offset+1, … from states (per mode as :func:`_store_block`).

    The states are either the rows of Y (``tq`` empty) or the DOP853 interpolant (segments
    ``seg_t``, ``seg_h``, ``coef``) at the times ``tq``, found by walking the segments once: ``tq`` is
    sorted along the direction of integration, or against it with ``reverse`` (then it is walked from
    its end, so no reversed copy is needed; row offset + q still receives time tq[q]).

    They go through blocks of ≤ _BLOCK samples of one segment, a column per sample: θ, then the interpolant
    component by component (vectorized over the samples), then :func:`_store_block`.  For a precessing run into χ₁,
    χ₂ and ℓ̂ arrays without rows (a waveform without spin terms, :mod:`pnrotor.waveform.stream`) the spins'
    components are not interpolated: v, Φ and R only.  A sample at a time with
    its 12 components as scalars took 60 ns on a precessing run (30 + 10 M☉ at 1/4096 s) and 34 ns on a
    nonspinning one (1.4 + 1.4 M☉), into outputs already touched; blocks take 28 and 22 ns, of which 13
    are ``sincos``.
    """
    dense = tq.size > 0
    nrow = tq.size if dense else Y.shape[0]
    n = min(coef.shape[2] if dense else Y.shape[1], layout.N_PRECESSING)   # not the masses: none is stored
    y = np.empty((n, _BLOCK))
    cs = np.empty((2, _BLOCK))
    if not dense:
        for q0 in range(0, nrow, _BLOCK):
            m = min(_BLOCK, nrow - q0)
            for b in range(m):
                for k in range(n):
                    y[k, b] = Y[q0 + b, k]
            _store_block(mode, y, cs, m, offset + q0, R0, ell0, c1, c2, v, Phi, chi1, chi2, R, ell)
        return
    theta = np.empty(_BLOCK)
    nseg = seg_t.size
    j = 0
    start = 0     # samples start … stop − 1 along the walk lie in segment j
    while start < nrow:
        t = tq[nrow - 1 - start if reverse else start]
        while j + 1 < nseg and (t - seg_t[j + 1]) * seg_h[j + 1] >= 0.0:
            j += 1
        stop = nrow
        if j + 1 < nseg:
            stop = start + 1
            while stop < nrow and (tq[nrow - 1 - stop if reverse else stop] - seg_t[j + 1]) * seg_h[j + 1] < 0.0:
                stop += 1
        qa, qb = (nrow - stop, nrow - start) if reverse else (start, stop)
        t0 = seg_t[j]
        h = seg_h[j]
        for q0 in range(qa, qb, _BLOCK):
            m = min(_BLOCK, qb - q0)
            for b in range(m):
                theta[b] = (tq[q0 + b] - t0) / h
            for k in range(n):
                if 1 <= k <= 6 and mode != MODE_ALIGNED and chi1.shape[0] == 0:   # the spins, not stored
                    continue
                for b in range(m):
                    y[k, b] = _contd8(coef, j, k, theta[b], 1.0 - theta[b])
            _store_block(mode, y, cs, m, offset + q0, R0, ell0, c1, c2, v, Phi, chi1, chi2, R, ell)
        start = stop


_NO_T = np.empty(0)
NO_Y = np.empty((0, 1))
_NO_SEG = np.empty(1)
_NO_COEF = np.empty((1, 8, 1))


PEAK_BYTES_PER_SAMPLE = {"precessing": 136, "aligned": 64}
"""Peak memory per output sample of a uniform or per-orbit sampling: :func:`sample`'s (the history and its times;
tracemalloc: 128 bytes on precessing runs, 56 on aligned ones, which store no rows of χ₁, χ₂, ℓ̂, both for runs of
1.2e5–3.5e5 samples either way) and the times in seconds the Evolution adds."""


def _check_memory(n, s):
    """ValueError naming ``sampling`` if ``n`` samples of run ``s`` would not fit in the memory available."""
    need = n * PEAK_BYTES_PER_SAMPLE["aligned" if s.use_aligned else "precessing"]
    free = processes.available_memory()
    if not need < free:
        what = f"{s.sampling_value!r} s" if s.sampling == "dt" else f"('per_orbit', {s.sampling_value!r})"
        stream = (", or write the history to a file block by block: pnrotor.hdf5.write(path, pnrotor.stream(m1, m2, "
                  "chi1, chi2, f_ref, delta_t=...).evolution()) (pnrotor evolve --sampling DT writes that way)"
                  if s.sampling == "dt" else "")
        raise ValueError(f"sampling = {what} would need {n:.4g} samples ({need / 2 ** 30:.3g} GiB), more than the "
                         f"{free / 2 ** 30:.3g} GiB of memory available now; choose a coarser sampling or a "
                         f"shorter span (f_min, f_max){stream}")


def allocate_history(n, mode=MODE_COPRECESSING):
    """(v, Φ, χ₁, χ₂, R, ℓ̂) arrays for n samples; for an aligned run (``mode``) χ₁, χ₂ and ℓ̂, constant, get no
    rows here (:func:`constant_rows`)."""
    rows = 0 if mode == MODE_ALIGNED else n
    return np.empty(n), np.empty(n), np.empty((rows, 3)), np.empty((rows, 3)), np.empty((n, 4)), np.empty((rows, 3))


def constant_rows(hist, mode, fixed, n):
    """The history with an aligned run's χ₁, χ₂ and ℓ̂ as read-only (n, 3) views of their one value: no memory per
    sample."""
    if mode != MODE_ALIGNED:
        return hist
    v, Phi, _, _, R, _ = hist
    _, ell0, c1, c2 = fixed
    return v, Phi, _repeated(c1, n), _repeated(c2, n), R, _repeated(ell0, n)


def _repeated(x, n):
    """The contiguous 3-vector x as a read-only (n, 3) view of it, repeated: what ``np.broadcast_to`` gives, at less
    cost."""
    view = np.ndarray((n, 3), np.float64, x, 0, (0, 8))
    view.flags.writeable = False
    return view


def fixed_parts(s):
    """The arguments of :func:`fill_history` that a run fixes: R₀, ℓ̂ and the spins at f_ref."""
    return np.ascontiguousarray(s.R0, dtype=np.float64), s.ell_hat, s.chi1, s.chi2


def compile_output_kernel(s):
    """Compile :func:`fill_history` (or load it from numba's cache) now, once per process, for the argument
    types :func:`sample` gives it.  :func:`pnrotor.pn.evolve.evolve` calls this before it integrates, so that on
    a cold cache it is compiled while another process compiles the DOP853 core (:mod:`pnrotor.numba_cache`),
    not after it; and so is :func:`_phase_roots` for a per-orbit run."""
    if not fill_history.overloads:
        fill_history(output_mode(s.use_aligned, s.rotor), _NO_SEG, _NO_SEG, _NO_COEF, _NO_T, False, NO_Y,
                      *fixed_parts(s), 0, *allocate_history(0))
    if s.sampling == "per_orbit" and not _phase_roots.overloads:
        _phase_roots(_NO_SEG, _NO_SEG, _NO_COEF, 0, _NO_T, 0.0, _NO_T)


def sample(s, res_f, res_b):
    """(t in M, (v, Φ, χ₁, χ₂, R, ℓ̂)) of the run with :class:`~pnrotor.pn.settings.Settings` ``s`` from its
    forward result ``res_f`` and backward result ``res_b`` (None if not integrated), at ``s.sampling``."""
    mode = output_mode(s.use_aligned, s.rotor)
    fixed = fixed_parts(s)
    if s.sampling in ("final", "steps"):
        return _sample_steps(s.sampling, mode, fixed, res_f, res_b)
    if res_b is not None and res_b.dense is None:
        res_b = None   # a backward half that took no step has no sample but t = 0, the forward half's
    if s.sampling == "dt":
        dt = s.sampling_value / s.M_sec
        _check_memory((t_end_of(res_f) - (0.0 if res_b is None else t_end_of(res_b))) / dt, s)
        t_out, nb = _uniform_times(dt, t_end_of(res_f), None if res_b is None else t_end_of(res_b))
    else:
        phi_i = layout.YA_PHI if s.use_aligned else layout.Y_PHI
        _check_memory((res_f.y[-1, phi_i] - (0.0 if res_b is None else res_b.y[-1, phi_i]))
                      * s.sampling_value / (2.0 * math.pi), s)
        t_out, nb = _orbit_times(s.sampling_value, phi_i, res_f, res_b)
    hist = allocate_history(t_out.size, mode)
    if nb:
        d = res_b.dense   # backward samples: visited from t = 0 downwards, the direction of integration
        fill_history(mode, d.seg_t, d.seg_h, d.coef, t_out[:nb], True, NO_Y, *fixed, 0, *hist)
    d = res_f.dense
    if d is None:   # no step taken forward (a step underflow at once, max_steps = 1): the state at t = 0 alone
        fill_history(mode, _NO_SEG, _NO_SEG, _NO_COEF, _NO_T, False, np.ascontiguousarray(res_f.y[:1]), *fixed, nb,
                      *hist)
    else:
        fill_history(mode, d.seg_t, d.seg_h, d.coef, t_out[nb:], False, NO_Y, *fixed, nb, *hist)
    return t_out, constant_rows(hist, mode, fixed, t_out.size)


def t_end_of(res):
    """Where a half's integration ended (0 if it took no step)."""
    return 0.0 if res.dense is None else res.dense.t_max


def _sample_steps(sampling, mode, fixed, res_f, res_b):
    """The accepted steps of both halves in time order ('steps'), or the last state ('final')."""
    if sampling == "final":
        parts = [(res_f.t[-1:], res_f.y[-1:])]
    else:
        parts = ([(res_b.t[:0:-1], res_b.y[:0:-1])] if res_b is not None else []) + [(res_f.t, res_f.y)]
    t_out = np.concatenate([tp for tp, _ in parts])
    hist = allocate_history(t_out.size, mode)
    off = 0
    for tp, Yp in parts:
        fill_history(mode, _NO_SEG, _NO_SEG, _NO_COEF, _NO_T, False, np.ascontiguousarray(Yp), *fixed, off, *hist)
        off += tp.size
    return t_out, constant_rows(hist, mode, fixed, t_out.size)


def uniform_range(dt, t_forward, t_backward):
    """(k_lo, k_hi): the first and last k with t = kΔt within the integrated span [t_backward or 0, t_forward]."""
    k_hi = math.floor(t_forward / dt * (1.0 + 1e-15))
    while k_hi * dt > t_forward:
        k_hi -= 1
    k_lo = 0
    if t_backward is not None:
        k_lo = math.ceil(t_backward / dt * (1.0 + 1e-15))
        while k_lo * dt < t_backward:
            k_lo += 1
    return k_lo, k_hi


def _uniform_times(dt, t_forward, t_backward):
    """(t = kΔt for every k within the integrated span [t_backward or 0, t_forward], ascending; how many are before
    t = 0)."""
    k_lo, k_hi = uniform_range(dt, t_forward, t_backward)
    t_out = np.arange(k_lo, k_hi + 1, dtype=np.float64)
    t_out *= dt                                   # one allocation: t = k Δt, ascending
    return t_out, -k_lo


def _orbit_times(per_orbit, phi_i, res_f, res_b):
    """(the times where Φ = 2πj/n within the integrated span, ascending; how many are before t = 0)."""
    step = 2.0 * math.pi / per_orbit
    phi_end = res_f.y[-1, phi_i]
    tf = np.zeros(1) if res_f.dense is None else \
        _phase_times(res_f.dense, phi_i, np.arange(0, math.floor(phi_end / step) + 1) * step)
    tf[0] = 0.0
    if res_b is not None:
        phi_start = res_b.y[-1, phi_i]
        tb = _phase_times(res_b.dense, phi_i, np.arange(math.ceil(phi_start / step), 0)[::-1] * step)[::-1]
    else:
        tb = np.empty(0)
    return np.concatenate((tb, tf)), tb.size


def _phase_times(dense, phi_index, targets):
    """Times at which Φ(t) of the dense output equals each target, for targets in the order of integration (Φ
    rises with t, so falls along a backward half): :func:`_phase_roots`."""
    targets = np.ascontiguousarray(targets, dtype=np.float64)   # the types of the one compiled signature
    t = np.empty(targets.size)
    _phase_roots(dense.seg_t, dense.seg_h, dense.coef, phi_index, targets, dense.t_max, t)
    return t


@njit(cache=True)
def _phase_roots(seg_t, seg_h, coef, i, targets, t_final, t):
    """t[q] = the time at which component i (Φ) of the DOP853 interpolant equals targets[q], for targets in the
    order of integration, along which Φ is monotonic: the segments are walked once, each target solved on the first
    segment whose end it does not pass, Φ(θ) = target by Newton's method in θ ∈ [0, 1] from the linear
    interpolation between the segment's ends, on the exact derivative of its polynomial (:func:`_contd8_slope`) and
    kept in a bracket (bisection where a Newton step would leave it), to |Δθ| ≤ 4e-16; t within the integrated span
    (a target rounded past its end gets t_final).  Measured (benchmarks/bench_latency.py, sample() with 4 samples
    per orbit): 62 ns per sample on a nonspinning run of 5,229 samples and 284 ns on a precessing one of 147 (its
    fixed costs), against 175 and 1,770 ns with Newton in numpy on ``DenseOutput`` calls."""
    sign = 1.0 if seg_h[0] > 0.0 else -1.0   # Φ rises with t
    nseg = seg_t.size
    j = 0
    for q in range(targets.size):
        target = targets[q]
        while j + 1 < nseg and sign * (target - (coef[j, 0, i] + coef[j, 1, i])) > 0.0:
            j += 1
        f0 = coef[j, 0, i] - target   # Φ(θ) − target at θ = 0 and 1 (contd8 is r₁ + r₂ at θ = 1)
        f1 = f0 + coef[j, 1, i]
        lo, hi = 0.0, 1.0
        theta = 0.0 if f0 == f1 else min(1.0, max(0.0, f0 / (f0 - f1)))
        for _ in range(60):
            value, slope = _contd8_slope(coef, j, i, theta)
            f = value - target
            if f == 0.0:
                break
            if (f > 0.0) == (sign > 0.0):   # past the target along the integration
                hi = theta
            else:
                lo = theta
            new = theta - f / slope if slope != 0.0 else -1.0
            if not lo < new < hi:
                new = 0.5 * (lo + hi)
            done = abs(new - theta) <= 4e-16
            theta = new
            if done or hi - lo <= 4e-16:
                break
        tq = seg_t[j] + theta * seg_h[j]
        t[q] = min(tq, t_final) if sign > 0.0 else max(tq, t_final)
