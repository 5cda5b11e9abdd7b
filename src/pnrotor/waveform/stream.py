r"""Long signals: a PN run's history, modes or polarizations computed block by block from the DOP853 dense output.

``pnrotor.evolve`` samples a whole history first (v, Φ, χ₁, χ₂, R, ℓ̂ and the times: 136 bytes a sample for a
precessing run), ``pnrotor.modes`` then forms every mode of every sample (16 bytes a mode and sample) and
``Modes.polarizations`` sums them: for a binary neutron star from 5 Hz at Δt = 1/4096 s (2.8·10⁷ samples) that is
3.8 GB of history and 34 GB of modes for ℓ ≤ 8, where the 16 bytes a sample of h₊, h× are what is wanted.
Here a run is integrated once (stages 1–3 of ``pnrotor.evolve``, its dense output kept: ~1 kB a step) on the grid
t = kΔt of ``sampling=Δt`` and nothing is computed per sample until asked:

* :func:`stream` → :class:`Stream`; its :meth:`~Stream.evolution`, :meth:`~Stream.modes` and
  :meth:`~Stream.polarizations` → :class:`Streamed`: ``block(lo, hi)`` the result of the samples lo … hi−1 (an
  :class:`~pnrotor.pn.evolve.Evolution`, :class:`~pnrotor.waveform.modes.Modes` or
  :class:`~pnrotor.results.Polarizations` of those samples alone), ``compute()`` all of them in
  memory (checked against the memory available first), and ``pnrotor.hdf5.write(path, streamed)`` (or
  ``Batch.add``) writes them 2¹⁷ samples at a time into chunked datasets: a file larger than memory, in bounded
  memory (~160 MB of modes a block for ℓ ≤ 8, 2 MB of polarizations);
* :func:`polarizations` and :func:`modes` (``pnrotor.polarizations``, ``pnrotor.modes`` with a binary's parameters)
  are the one-call forms.

The modes and polarizations of a block are one compiled pass, :func:`_waves`, on the threads of
:mod:`pnrotor.threads` (parts of ≥ 1 ms of work, :func:`pnrotor.threads.run_timed`): per block of 256 samples
(``wigner.CHUNK``) the states from the dense output (:func:`pnrotor.pn.sampling.fill_history`, the kernel of
``evolve``'s sampling, on the segments from the block's first), the co-orbital amplitudes and their rotation by
𝔇 (:func:`pnrotor.waveform.amplitudes.block_start`, :func:`~pnrotor.waveform.amplitudes.block_ell`), then either
the inertial modes stored, or, for h₊ − i h× = Σ_ℓm h_ℓm ₋₂Y_ℓm(ι, π/2 − φ_ref), the rotation taken to the frame of
the line of sight, where the sum over m is its m = 2 term alone (:func:`_line_of_sight`): one mode per ℓ of the
rotation's second product, summed at once, so a polarizations call forms neither a history nor a mode array.  A run
whose rotors turn about ẑ alone (aligned spins in the default frame) has no rotation to make: its inertial modes
H_ℓm e^{−imΦ} are summed with their ₋₂Y_ℓm as they are formed (:func:`_harmonics`; less time a sample than
the rotation).
The history of :meth:`Stream.evolution` is ``fill_history`` itself, a block at a time.

The numbers are those of ``evolve(…, sampling=Δt)`` → ``modes(run, …)`` → ``Modes.polarizations(ι, φ_ref)``: the
history and the modes bitwise (the same kernels on the same samples in the same blocks of 256: the parts and blocks
start at multiples of 256), the polarizations to rounding (another rotation of the same modes; ≤ 2e-15 of max|h| on
the tests' BBH, NSBH and BNS, which allow 1e-13; summing all the inertial modes, as ``Modes.polarizations`` does,
would give them bitwise at a higher cost), those of a run in frame "z" bitwise (that sum, term by term, tested on
aligned and nonspinning BBH and BNS).  ``pnrotor.threads`` splits the samples, so the thread count does not change
any of them.  The kernel holds
``fill_history`` (:mod:`pnrotor.pn.sampling`), the block functions of :mod:`pnrotor.waveform.amplitudes` and
:func:`pnrotor.waveform.wigner.store` (numba caches per source file): after editing those, remove this module's
``__pycache__/stream.*.nb*``.
"""

import math
import mmap
import time

import numpy as np
from numba import njit

from pnrotor import processes, threads
from pnrotor.pn import initial as _ini
from pnrotor.pn import sampling as _sampling
from pnrotor.pn.evolve import OPTIONS, Evolution, integrate
from pnrotor.pn.sampling import MODE_ALIGNED, fill_history
from pnrotor.pn.settings import settings
from pnrotor.waveform import amplitudes as _amp
from pnrotor.waveform.layout import mode_index, n_modes
from pnrotor.results.waves import Modes, Polarizations, angle
from pnrotor.values import real
from pnrotor.waveform.distance import scale as _scale
from pnrotor.waveform.modes import ELL_MAX, check_arguments, check_memory_flag, spins_and_frame, tides_of, wave_inputs
from pnrotor.waveform import polarizations as _pol
from pnrotor.waveform.modes import modes as modes_of_run
from pnrotor.waveform.wigner import CHUNK, store

__all__ = ["stream", "Stream", "Streamed", "polarizations", "modes"]

AMPLITUDE_ORDER = 3.5
"""The default amplitude order, as :func:`pnrotor.modes`'."""


def stream(m1, m2, chi1, chi2, f_ref, *, delta_t, f_min=None, f_max=None, **keywords):
    """The binary of ``pnrotor.evolve(m1, m2, chi1, chi2, f_ref, f_min=…, f_max=…, sampling=delta_t, **keywords)``
    integrated (its stages 1–3), its samples t = k Δt (``delta_t`` in seconds, or an astropy time) not computed
    yet: a :class:`Stream`.  ``keywords`` are evolve's other keywords (the frame, κᵢ, Λᵢ, ``options`` and the fields
    of :class:`pnrotor.Options`: approximant, orders, tolerances, …)."""
    wall0 = time.perf_counter()
    if "sampling" in keywords:
        raise TypeError("stream() got an unexpected keyword argument 'sampling' (delta_t is its sampling)")
    delta_t = _ini.seconds(delta_t, "delta_t")
    s = settings(m1, m2, chi1, chi2, f_ref, "stream", **{**OPTIONS, **keywords, "f_min": f_min, "f_max": f_max,
                                                          "sampling": delta_t})
    res_f, res_b, termination, stats = integrate(s)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Stream(s, res_f, res_b, termination, stats)


_NO_SEG = np.empty(1)
_NO_COEF = np.empty((1, 8, 1))


def _segments(res):
    """(seg_t, seg_h, coef) of a half's dense output: empty ones (a segment of nothing) for a half not integrated or
    without a step, but a forward half without one, whose state at t = 0 is one segment of θ = 0 (r₁ + 0 … = r₁)."""
    if res is None:
        return _NO_SEG, _NO_SEG, _NO_COEF
    d = res.dense
    if d is None:
        coef = np.zeros((1, 8, res.y.shape[1]))
        coef[0, 0] = res.y[0]
        return np.zeros(1), np.ones(1), coef
    return d.seg_t, d.seg_h, d.coef


class Stream:
    """A PN run integrated on the grid t = k Δt of its ``sampling`` (:func:`stream`), its samples computed when asked:
    ``len(stream)`` samples (t = 0 at f_ref); ``termination``, ``stats`` and ``inputs`` as
    the :class:`~pnrotor.pn.evolve.Evolution`'s (``stats['wall_time_s']`` up to the integration).  Its
    :meth:`evolution`, :meth:`modes` and :meth:`polarizations` are :class:`Streamed`."""

    def __init__(self, s, res_f, res_b, termination, stats):
        if res_b is not None and res_b.dense is None:
            res_b = None   # a backward half that took no step has no sample but t = 0, the forward half's
        self.settings, self.termination, self.stats, self.inputs = s, termination, stats, s.inputs()
        self._dt = s.sampling_value / s.M_sec
        t_end = _sampling.t_end_of
        k_lo, k_hi = _sampling.uniform_range(self._dt, t_end(res_f), None if res_b is None else t_end(res_b))
        self._k_lo, self._n, self._n_back = k_lo, k_hi - k_lo + 1, -k_lo
        self._forward, self._backward = _segments(res_f), _segments(res_b)
        self._mode = _sampling.output_mode(s.use_aligned, s.rotor)
        self._fixed = _sampling.fixed_parts(s)

    def __len__(self):
        return self._n

    def _times(self, lo, hi):
        """t = k Δt in M of samples lo … hi−1 (as ``evolve``'s: k as a float times Δt)."""
        t = np.arange(self._k_lo + lo, self._k_lo + hi, dtype=np.float64)
        t *= self._dt
        return t

    def _history(self, lo, hi):
        """The Evolution of samples lo … hi−1, by evolve's sampling kernel."""
        s, mode, fixed = self.settings, self._mode, self._fixed
        t = self._times(lo, hi)
        hist = _sampling.allocate_history(t.size, mode)
        split = min(max(self._n_back - lo, 0), t.size)   # the backward half's samples come first
        if split:
            fill_history(mode, *self._backward, t[:split], True, _sampling.NO_Y, *fixed, 0, *hist)
        if split < t.size:
            fill_history(mode, *self._forward, t[split:], False, _sampling.NO_Y, *fixed, split, *hist)
        v, Phi, chi1, chi2, R, ell = _sampling.constant_rows(hist, mode, fixed, t.size)
        return Evolution(t=t, t_seconds=t * s.M_sec, v=v, Phi=Phi, chi1=chi1, chi2=chi2, R=R, ell_hat=ell,
                         termination=self.termination, stats=dict(self.stats), inputs=dict(self.inputs))

    def evolution(self):
        """The run's history (``pnrotor.evolve``'s :class:`~pnrotor.pn.evolve.Evolution` with ``sampling=Δt``,
        bitwise), :class:`Streamed`."""
        bytes_per_sample = _sampling.PEAK_BYTES_PER_SAMPLE["aligned" if self.settings.use_aligned else "precessing"]
        return Streamed(self, "Evolution", self._history, bytes_per_sample,
                        "evolution()", "a larger delta_t or a shorter span (f_min, f_max)")

    def modes(self, ell_max=ELL_MAX, amplitude_order=AMPLITUDE_ORDER, distance=None, tidal_order=None, memory=False):
        """The inertial modes of ``pnrotor.modes(evolution, ell_max, amplitude_order, distance, tidal_order, memory)``
        (bitwise), :class:`Streamed`: a :class:`~pnrotor.waveform.modes.Modes` of any of the run's samples."""
        ell_max, order2, distance_Mpc = check_arguments(ell_max, amplitude_order, distance)
        tides, memory = tides_of(self.inputs, tidal_order), check_memory_flag(memory)
        inputs = dict(self.inputs, ell_max=ell_max, amplitude_order=order2 / 2,
                      distance_Mpc=np.nan if distance_Mpc is None else distance_Mpc, **wave_inputs(tides, memory))
        scale = 1.0 if distance_Mpc is None else _scale(None, distance_Mpc, self.settings.M_sec)
        args, _ = self._wave_arguments(ell_max, order2, scale, tides, memory)
        count = n_modes(ell_max)

        def block(lo, hi):
            t, t_s, Phi, R = _empty(hi - lo), _empty(hi - lo), _empty(hi - lo), _empty((hi - lo, 4))
            data = _empty((count, hi - lo), np.complex128)
            self._run(args, _NONE, (t, t_s, Phi, R, data.view(np.float64), _NONE, _NONE), lo, hi)
            return Modes(t=t, t_seconds=t_s, ell_max=ell_max, data=data, frame="inertial", R=R, Phi=Phi,
                         distance_Mpc=distance_Mpc, inputs=dict(inputs))

        return Streamed(self, "Modes", block, 16 * count + 56, f"modes(ell_max={ell_max}, ...)",
                        "a smaller ell_max, a larger delta_t or a shorter span (f_min, f_max)")

    def polarizations(self, *, inclination, distance, phi_ref=0.0, ell_max=ELL_MAX, amplitude_order=AMPLITUDE_ORDER,
                      tidal_order=None, memory=False):
        """h₊, h× of ``pnrotor.modes(evolution, ell_max, amplitude_order, distance, tidal_order,
        memory).polarizations(inclination, phi_ref)`` (the direction (ι, π/2 − φ_ref) of the inertial frame, LALSuite's convention; strain at
        ``distance`` in Mpc or an astropy length; angles in radians or astropy angles), :class:`Streamed`: a
        :class:`~pnrotor.results.Polarizations` of any of the run's samples.  Summed in the frame of
        the line of sight, where only the modes m = 2 count (:func:`_line_of_sight`)."""
        ell_max, order2, distance_Mpc = check_arguments(ell_max, amplitude_order, distance)
        if distance_Mpc is None:
            raise ValueError("distance is required: h+ and hx are strain at that distance (Mpc, or an astropy length)")
        inclination, phi_ref = angle(inclination, "inclination"), angle(phi_ref, "phi_ref")
        tides, memory = tides_of(self.inputs, tidal_order), check_memory_flag(memory)
        args, weights = self._wave_arguments(ell_max, order2, _scale(None, distance_Mpc, self.settings.M_sec), tides,
                                             memory, (inclination, 0.5 * np.pi - phi_ref))
        inputs = dict(self.inputs, ell_max=ell_max, amplitude_order=order2 / 2, **wave_inputs(tides, memory))

        def block(lo, hi):
            t_s, hp, hc = _empty(hi - lo), _empty(hi - lo), _empty(hi - lo)
            self._run(args, weights, (_NONE, t_s, _NONE, _NO_ROTORS, _NO_MODES, hp, hc), lo, hi)
            return Polarizations(t_seconds=t_s, h_plus=hp, h_cross=hc, inclination=inclination, phi_ref=phi_ref,
                                 distance_Mpc=distance_Mpc, inputs=dict(inputs))

        return Streamed(self, "Polarizations", block, 24, f"polarizations(ell_max={ell_max}, ...)",
                        "a larger delta_t or a shorter span (f_min, f_max)")

    def _wave_arguments(self, ell_max, order2, scale, tides, memory, direction=None):
        """The arguments of :func:`_waves` fixed by the run and the modes asked for, up to its weights and outputs, and
        its weights: for the inertial modes (none), or, given the ``direction`` (ι, φ) of a line of sight, for the
        polarizations seen from it: of a run whose rotors turn about ẑ alone (frame "z": an aligned run in the default
        frame, h_ℓm = H_ℓm e^{−imΦ}) the inertial modes' ₋₂Y_ℓm(ι, φ) (:func:`_harmonics`), else the rotor R_n of the
        line of sight and w_ℓ (:func:`_line_of_sight`), for the modes in the frame R_n⁻¹ R whose m = 2 the
        polarizations take (only those of the rotation's second product)."""
        s, inputs = self.settings, self.inputs
        if s.use_aligned:
            chi1, chi2, frame = spins_and_frame(inputs, s.chi1, s.chi2, s.ell_hat)
            spins, constant = 0, None if chi1 is None else (chi1, chi2)
        else:
            spins, frame, constant = 2, "rotors", None
        *terms, first, rows, coefs = _amp.kernel_terms(s.m1, s.m2, ell_max, order2, s.kappa1, s.kappa2,
                                                       inputs["spin_content"] != "nonspinning", constant, tides,
                                                       memory)
        if not np.any(terms[10] > _amp.Q_LOG):   # no term of a spin quantity (kernel_terms' q) at this order: the
            spins = 0                            # spins are not taken into the orbital frame per sample
        Rn, weights = _NONE, _NONE
        if direction is not None and frame == "z":
            weights = _harmonics(*direction, ell_max, *terms[7:9])   # kernel_terms' ell_start, target
        elif direction is not None:
            Rn, weights = _line_of_sight(*direction, ell_max)
            frame = "rotors"
            first, rows, coefs = _m2_plan(first, rows, coefs, ell_max)
        return (self._mode, *self._forward, *self._backward, self._n_back, self._k_lo, self._dt, s.M_sec,
                *self._fixed, Rn, spins, _amp.FRAME_CODES[frame], float(scale), *terms, first, rows, coefs), weights

    def _run(self, args, weights, outputs, lo, hi):
        """:func:`_waves` over samples lo … hi−1 into ``outputs`` (those of sample lo first), in parts on the
        threads."""
        if not getattr(_waves, "overloads", True):   # the CLI may be compiling it aside: load it, not compile twice
            from pnrotor import numba_cache

            numba_cache.wait_for_aside("waves")
        call = (*args, weights, *outputs, lo)
        threads.run_timed(lambda a, b: _waves(*call, lo + a, lo + b), hi - lo, CHUNK)


def _line_of_sight(inclination, phi, ell_max):
    """(R_n, w): the rotor R_n = exp(φẑ/2) exp(ιŷ/2), which takes ẑ to the direction (ι, φ), and w_ℓ = √((2ℓ+1)/(4π))
    for ℓ = 0 … ell_max, such that Σ_m ₋₂Y_ℓm(ι, φ) 𝔇^ℓ_{m m'}(R_n) = w_ℓ δ_{m' 2} (seen from its own pole a
    spin-weight −2 harmonic has only m = 2; Goldberg et al. 1967, the harmonics as rows of 𝔇; checked in
    tests/test_waveform_stream.py).  So with h = 𝔇(R) H and 𝔇(R_n)𝔇(R_n⁻¹ R) = 𝔇(R),

        h₊ − i h× = Σ_ℓm h_ℓm ₋₂Y_ℓm(ι, φ) = Σ_ℓ w_ℓ h'_ℓ2,     h' = 𝔇(R_n⁻¹ R) H,

    one mode per ℓ of the rotation to the frame R_n⁻¹ R instead of all 2ℓ + 1 of the inertial frame and their
    sum (the numbers of the inertial modes' sum to rounding)."""
    c, s = math.cos(0.5 * phi), math.sin(0.5 * phi)
    ci, si = math.cos(0.5 * inclination), math.sin(0.5 * inclination)
    Rn = np.array([c * ci, -s * si, c * si, s * ci])   # (c, 0, 0, s)(ci, 0, si, 0)
    return Rn, np.sqrt((2.0 * np.arange(ell_max + 1) + 1.0) / (4.0 * math.pi))


def _harmonics(inclination, phi, ell_max, ell_start, target):
    """₋₂Y_ℓm(ι, φ) of the modes ℓ ≤ ell_max (:func:`pnrotor.waveform.polarizations.swsh`), as (re, im) pairs in
    :func:`~pnrotor.waveform.layout.mode_index` order, h₊ − i h× = Σ_ℓm h_ℓm ₋₂Y_ℓm being what
    :meth:`~pnrotor.waveform.modes.Modes.polarizations` sums; 0 for the modes no amplitude term of
    :func:`~pnrotor.waveform.amplitudes.kernel_terms` (``ell_start``, ``target``: rows ℓ ± m of its block array) reaches,
    which the kernel skips."""
    n_pow = 2 * ell_max + 1
    out = np.zeros((n_modes(ell_max), 2))
    for ell in range(2, ell_max + 1):
        for m in {abs(int(t) % n_pow - ell) for t in target[ell_start[ell]:ell_start[ell + 1]]}:
            for sign in (1, -1) if m else (1,):
                y = complex(_pol.swsh(-2, ell, sign * m, inclination, phi))
                out[mode_index(ell, sign * m)] = y.real, y.imag
    return out.ravel()


def _m2_plan(first, rows, coefs, ell_max):
    """The rotation plan (:func:`pnrotor.waveform.wigner.rotation_plan`) with, of each ℓ's second product, only the
    passes that give the rows ℓ ± 2 (m = ±2)."""
    keep, new_first = [], np.zeros_like(first)
    for ell in range(2, ell_max + 1):
        new_first[2 * ell] = len(keep)
        keep += range(first[2 * ell], first[2 * ell + 1])
        new_first[2 * ell + 1] = len(keep)
        keep += [k for k in range(first[2 * ell + 1], first[2 * ell + 2]) if rows[k, 0] == ell + 2]
        new_first[2 * ell + 2:] = len(keep)
    return new_first, np.ascontiguousarray(rows[keep]), np.ascontiguousarray(coefs[keep])


_HUGE_PAGES_FROM = 1 << 22
"""Bytes from which numpy asks Linux for transparent huge pages for an array (numpy's ``madvise`` threshold)."""


def _empty(shape, dtype=np.float64):
    """A new C-contiguous array for the kernel to fill; from :data:`_HUGE_PAGES_FROM` bytes in anonymous memory of the
    system's base pages (``mmap``) rather than numpy's: numpy asks for transparent huge pages there, and on some
    virtual machines their first touch costs several times the system time of base pages
    (benchmarks/bench_long.py; LAL's arrays, from malloc, get base pages).  Freed with the array."""
    count = int(np.prod(shape))
    size = count * np.dtype(dtype).itemsize
    if size < _HUGE_PAGES_FROM:   # below it a system call would cost more than it saves
        return np.empty(shape, dtype)
    return np.frombuffer(mmap.mmap(-1, size), dtype=dtype, count=count).reshape(shape)


_NONE = np.empty(0)
_NO_ROTORS = np.empty((0, 4))
_NO_MODES = np.empty((0, 0))


class Streamed:
    """A result of a :class:`Stream` (its ``kind``: ``"Evolution"``, ``"Modes"`` or ``"Polarizations"``), computed
    when asked: ``len(streamed)`` samples; :meth:`block` those of a range, :meth:`compute` all of them in memory;
    ``pnrotor.hdf5.write(path, streamed)`` writes them block by block (docs/hdf5-schema.md)."""

    def __init__(self, source, kind, block, bytes_per_sample, call, smaller):
        self.source, self.kind, self._block = source, kind, block
        self.bytes_per_sample, self._call, self._smaller = bytes_per_sample, call, smaller

    def __len__(self):
        return len(self.source)

    def block(self, lo, hi):
        """The result of samples lo … hi−1 (0 ≤ lo < hi ≤ len): an Evolution, Modes or Polarizations of them alone,
        the numbers of the whole run's (blocks starting at multiples of 256 take the whole run's blocks exactly)."""
        if not (isinstance(lo, (int, np.integer)) and isinstance(hi, (int, np.integer)) and 0 <= lo < hi <= len(self)):
            raise ValueError(f"block needs integers 0 <= lo < hi <= {len(self)}; got lo = {lo!r}, hi = {hi!r}")
        return self._block(int(lo), int(hi))

    def compute(self):
        """All the samples in memory, once checked to fit (a ValueError naming the ways to fewer samples and the
        streaming write otherwise, before allocating)."""
        need, free = self.bytes_per_sample * len(self), processes.available_memory()
        if not need < free:
            raise ValueError(f"{self.kind}: {len(self)} samples would need {need / 2 ** 30:.3g} GiB, more than the "
                             f"{free / 2 ** 30:.3g} GiB of memory available now; choose {self._smaller}, or write them "
                             f"to a file block by block: pnrotor.hdf5.write(path, pnrotor.stream(m1, m2, chi1, chi2, "
                             f"f_ref, delta_t=...).{self._call}) (pnrotor evolve --sampling DT writes that way)")
        return self._block(0, len(self))


def polarizations(m1, m2, chi1, chi2, f_ref, *, inclination, distance, delta_t, phi_ref=0.0, f_min=None, f_max=None,
                  ell_max=ELL_MAX, amplitude_order=AMPLITUDE_ORDER, memory=False, **keywords):
    """(t, h₊, h×), float64 arrays: the polarizations of the binary (``pnrotor.evolve``'s parameters; ``keywords`` its
    other keywords, ``options`` and the fields of :class:`pnrotor.Options` among them) seen at ``inclination`` and
    ``phi_ref`` (radians or astropy angles; the direction (ι, π/2 − φ_ref) of the inertial frame, LALSuite's
    convention) as strain at ``distance`` (Mpc or an astropy length), at t = k
    ``delta_t`` seconds (t = 0 at f_ref, from f_min, if given, to f_max or the end of the inspiral: ``evolve``'s time
    axis with ``sampling=delta_t``), from the modes ℓ ≤ ``ell_max`` with amplitude terms through ``amplitude_order``
    (and the run's tidal terms; with ``memory``, the nonlinear memory: :func:`pnrotor.modes`).

    The numbers of ``pnrotor.modes(pnrotor.evolve(…, sampling=delta_t), ell_max, amplitude_order,
    distance).polarizations(inclination, phi_ref)``, computed in one pass from the integrator's dense output without
    forming the history or the modes (module docstring): 24 bytes a sample in all.  For a signal larger than memory,
    ``pnrotor.hdf5.write(path, pnrotor.stream(…).polarizations(…))``."""
    check_arguments(ell_max, amplitude_order, distance)   # before integrating
    check_memory_flag(memory)
    p = stream(m1, m2, chi1, chi2, f_ref, delta_t=delta_t, f_min=f_min, f_max=f_max, **keywords).polarizations(
        inclination=inclination, distance=distance, phi_ref=phi_ref, ell_max=ell_max,
        amplitude_order=amplitude_order, memory=memory).compute()
    return p.t_seconds, p.h_plus, p.h_cross


def modes(m1, *args, **kwargs):
    """Inertial-frame modes h_ℓm as :class:`~pnrotor.waveform.modes.Modes` (``pnrotor.modes``), of a run or of a binary:

    * ``modes(evolution, ell_max=8, amplitude_order=3.5, distance=None, tidal_order=None, memory=False)``: of the
      samples of an :class:`~pnrotor.pn.evolve.Evolution` (:func:`pnrotor.waveform.modes.modes`);
    * ``modes(m1, m2, chi1, chi2, f_ref, *, delta_t, distance=None, f_min=None, f_max=None, ell_max=8,
      amplitude_order=3.5, memory=False, **keywords)`` (``keywords``: evolve's other keywords, ``options`` and the
      fields of :class:`pnrotor.Options` among them): those of ``pnrotor.modes(pnrotor.evolve(…,
      sampling=delta_t), ell_max, amplitude_order, distance, memory=memory)``, bitwise, computed in one pass from the
      integrator's dense output without forming its history."""
    if isinstance(m1, Evolution):
        return modes_of_run(m1, *args, **kwargs)
    if not (real(m1) or hasattr(m1, "unit")):   # a mass: a number, or an astropy Quantity
        raise TypeError(f"modes() takes an Evolution (what pnrotor.evolve returns, or pnrotor.hdf5.read reads) or a "
                        f"binary's m1, m2, chi1, chi2, f_ref with delta_t=..., got {type(m1).__name__}")
    return _binary_modes(m1, *args, **kwargs)


def _binary_modes(m1, m2, chi1, chi2, f_ref, *, delta_t, distance=None, f_min=None, f_max=None, ell_max=ELL_MAX,
                  amplitude_order=AMPLITUDE_ORDER, memory=False, **keywords):
    """:func:`modes` of a binary."""
    check_arguments(ell_max, amplitude_order, distance)
    check_memory_flag(memory)
    return stream(m1, m2, chi1, chi2, f_ref, delta_t=delta_t, f_min=f_min, f_max=f_max, **keywords).modes(
        ell_max, amplitude_order, distance, memory=memory).compute()


@njit(cache=True)
def _segment(seg_t, seg_h, t):
    """The segment of a half's dense output that holds time t: the last whose start t has reached along the direction
    of integration (where :func:`pnrotor.pn.sampling.fill_history`'s walk puts t; its first if none)."""
    lo, hi = 0, seg_t.size - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if (t - seg_t[mid]) * seg_h[mid] >= 0.0:
            lo = mid
        else:
            hi = mid - 1
    return lo


@njit(cache=True, fastmath={"contract"})
def _add_times(x, r, yr, yi, acc_re, acc_im, nb):
    """acc += (row r of x, complex numbers as (re, im) pairs) × (yr + i yi), the product rounded before it is added."""
    for s in range(nb):
        xr, xi = x[r, 2 * s], x[r, 2 * s + 1]
        pr = xr * yr - xi * yi
        pi = xr * yi + xi * yr
        acc_re[s] += pr
        acc_im[s] += pi


@njit(cache=True)
def _times_rotor(a, R, nb, out):
    """Rows of out = a R[b] (Hamilton product) for b < nb."""
    for b in range(nb):
        out[b, 0] = a[0] * R[b, 0] - a[1] * R[b, 1] - a[2] * R[b, 2] - a[3] * R[b, 3]
        out[b, 1] = a[0] * R[b, 1] + a[1] * R[b, 0] + a[2] * R[b, 3] - a[3] * R[b, 2]
        out[b, 2] = a[0] * R[b, 2] - a[1] * R[b, 3] + a[2] * R[b, 0] + a[3] * R[b, 1]
        out[b, 3] = a[0] * R[b, 3] + a[1] * R[b, 2] - a[2] * R[b, 1] + a[3] * R[b, 0]


@njit(cache=True, nogil=True)
def _waves(mode, fwd_t, fwd_h, fwd_c, back_t, back_h, back_c, n_back, k_lo, dt, M_sec, R0, ell0, c1, c2, Rn, spins,
           frame, scale, h0, logs, X1, X2, kappa1, kappa2, ell_max, ell_start, target, k, q, c, first, rows, coefs,
           weights, t, t_s, Phi, R, modes, hp, hc, base, lo, hi):
    """Samples lo … hi−1 (lo a multiple of CHUNK: the blocks of the whole run) of the run whose halves' dense outputs
    are (fwd_*, back_*), n_back samples before t = 0, t = (k_lo + i) dt, into outputs whose row 0 is sample ``base``
    (an output of size 0 is not written): t (M), t_s (s), Phi, R (N, 4), and either the inertial modes (``modes``,
    a float view (n_modes, 2N) of complex (n_modes, N)) or h₊ and h× = Re, −Im of: given the rotor Rn of a line of
    sight, Σ_ℓ weights[ℓ] h'_ℓ2 of the modes h' in the frame Rn⁻¹ R (:func:`_line_of_sight`; the plan gives only
    their m = ±2), else (frame "z") Σ_ℓm h_ℓm Y_ℓm of the inertial modes with Y_ℓm = weights[2i] + i weights[2i + 1],
    i the mode's index, those with Y_ℓm = 0 skipped (:func:`_harmonics`); ``scale`` multiplies the modes as they are
    stored.  The other arguments are
    :func:`pnrotor.pn.sampling.fill_history`'s (mode, R0, ell0, c1, c2) and
    :func:`pnrotor.waveform.amplitudes._sum`'s (spins 0 or 2, frame, and
    :func:`~pnrotor.waveform.amplitudes.kernel_terms`)."""
    B = CHUNK
    n_rows = 0 if mode == MODE_ALIGNED or spins == 0 else B   # an aligned run's spins and ℓ̂ are constant, and
    # without spin terms neither is used: no rows (the states then have v, Φ and R alone)
    tq = np.empty(B)
    v_b, Phi_b, R_b, F_b = np.empty(B), np.empty(B), np.empty((B, 4)), np.empty((B, 4))
    chi1_b, chi2_b, ell_b = np.empty((n_rows, 3)), np.empty((n_rows, 3)), np.empty((n_rows, 3))
    no_y = np.empty((0, 1))
    w = _amp.workspace(ell_max, k, B)
    xs, cs = np.empty(3), np.empty(3)
    quadratic = np.any(q >= _amp.Q_P)
    x = np.empty((1, 2 * B))
    acc_re, acc_im = np.empty(B), np.empty(B)
    Rn_inv = np.empty(4)
    if Rn.size:
        Rn_inv[0], Rn_inv[1], Rn_inv[2], Rn_inv[3] = Rn[0], -Rn[1], -Rn[2], -Rn[3]
    for i0 in range(lo, hi, B):
        nb = min(B, hi - i0)
        o = i0 - base
        for b in range(nb):
            tq[b] = float(k_lo + i0 + b) * dt
        split = min(max(n_back - i0, 0), nb)
        if split > 0:   # walked from t = 0 down, as the backward half was integrated
            j = _segment(back_t, back_h, tq[split - 1])
            fill_history(mode, back_t[j:], back_h[j:], back_c[j:], tq[:split], True, no_y, R0, ell0, c1, c2, 0, v_b,
                          Phi_b, chi1_b, chi2_b, R_b, ell_b)
        if split < nb:
            j = _segment(fwd_t, fwd_h, tq[split])
            fill_history(mode, fwd_t[j:], fwd_h[j:], fwd_c[j:], tq[split:nb], False, no_y, R0, ell0, c1, c2, split,
                          v_b, Phi_b, chi1_b, chi2_b, R_b, ell_b)
        if t.size:
            t[o:o + nb] = tq[:nb]
        if t_s.size:
            for b in range(nb):
                t_s[o + b] = tq[b] * M_sec
        if Phi.size:
            Phi[o:o + nb] = Phi_b[:nb]
        if R.shape[0]:
            R[o:o + nb] = R_b[:nb]
        if modes.shape[0] == 0 and hp.size == 0:
            continue
        F = R_b
        if Rn.size:
            _times_rotor(Rn_inv, R_b, nb, F_b)
            F = F_b
        _amp.block_start(w, xs, cs, v_b, chi1_b, chi2_b, R_b, F, spins, frame, h0, logs, quadratic, X1, X2, kappa1,
                          kappa2, 0, nb)
        acc_re[:] = 0.0
        acc_im[:] = 0.0
        for ell in range(2, ell_max + 1):
            o_re, o_im, e_re, e_im = _amp.block_ell(w, ell, frame, ell_start, target, k, q, c, first, rows, coefs, nb)
            if Rn.size:   # h'_ℓ2 = e_2 o_{ℓ+2}, weighted
                store(o_re, o_im, ell + 2, e_re, e_im, 2, False, scale, x, 0, 0, nb)
                _add_times(x, 0, weights[ell], 0.0, acc_re, acc_im, nb)
                continue
            row0 = mode_index(ell, -ell)
            for r in range(2 * ell + 1):
                if hp.size == 0:
                    store(o_re, o_im, r, e_re, e_im, abs(r - ell), r < ell, scale, modes, row0 + r, o, nb)
                    continue
                y_re, y_im = weights[2 * (row0 + r)], weights[2 * (row0 + r) + 1]
                if y_re != 0.0 or y_im != 0.0:   # h_ℓm ₋₂Y_ℓm (frame "z": the inertial modes)
                    store(o_re, o_im, r, e_re, e_im, abs(r - ell), r < ell, scale, x, 0, 0, nb)
                    _add_times(x, 0, y_re, y_im, acc_re, acc_im, nb)
        if hp.size:
            for b in range(nb):
                hp[o + b] = acc_re[b]
                hc[o + b] = -acc_im[b]


def compile_kernels():
    """Compile :func:`_waves` (or load it from numba's cache) with one-sample calls for modes and for polarizations
    (every run gives it the same types; the state here is v = 0.3, R = 1, no spins): what
    :func:`pnrotor.numba_cache.compile_aside` runs in another process for a CLI run that writes modes or polarizations
    on a cold cache (a run here would compile the integrator a second time)."""
    coef = np.zeros((1, 8, 12))
    coef[0, 0, 0], coef[0, 0, 7] = 0.3, 1.0
    fixed = (np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), np.zeros(3), np.zeros(3))
    terms = _amp.kernel_terms(1.0, 1.0, 2, 0, 1.0, 1.0, True)
    head = (_sampling.MODE_COPRECESSING, np.zeros(1), np.ones(1), coef, _NO_SEG, _NO_SEG, _NO_COEF, 0, 0, 1.0, 1.0,
            *fixed)
    one = (np.empty(1), np.empty(1), np.empty(1), np.empty((1, 4)))
    _waves(*head, _NONE, 2, 2, 1.0, *terms, _NONE, *one, np.empty((5, 2)), _NONE, _NONE, 0, 0, 1)
    Rn, weights = _line_of_sight(0.0, 0.0, 2)
    *terms, first, rows, coefs = terms
    _waves(*head, Rn, 2, 2, 1.0, *terms, *_m2_plan(first, rows, coefs, 2), weights, _NONE, one[1], _NONE, _NO_ROTORS,
           _NO_MODES, np.empty(1), np.empty(1), 0, 0, 1)
