"""Modes of precessing binaries against LALSuite's SpinTaylorT4 modes (issue 13's cross-check).

LAL: ``SimInspiralChooseTDModes(phiRef=0, Δt, m1, m2, χ₁, χ₂, f_min, f_ref=f_min, r, LALparams, lmax=4,
SpinTaylorT4)`` with PN amplitude order 3 (1.5PN) in LALparams: its orbit from f_min with L̂N = ẑ,
E1 = x̂, and inertial modes computed directly from L̂N, E1, Φ and χᵢ through the inclination-angle
formulas of Arun et al. 2009 (arXiv:0810.5336, App. B).  pnrotor: the same orbit
(``lalsuite_orders("T4")``, ℓ̂ = ẑ, n̂ = x̂, Δt sampling from f_ref) and ``modes(…, ell_max=4,
amplitude_order=1.5)``: co-orbital amplitudes rotated by the evolved rotor through Wigner matrices, an
independent route to the same modes.

Goal (issue 13): every mode within 1e-4 of max|h₂₂| over v ≤ 0.4.  Measured (lalsuite 7.26.16, per case and
ℓ in `MEASURED`, each bounded at `FACTOR` times it, issue 37): ≤ 4.7e-7 for every mode of nonspinning and
aligned binaries; for precessing ones (2, ±2) differ by 4.7e-6 to 1.6e-5 (already with Newtonian amplitudes,
8.3e-6 for q3-precessing, largest mid-inspiral, while the orbit agrees to 1e-8 rad: LALSuite's mode
construction), the others of ℓ = 2 and 4 by ≤ 3.8e-7.  The ℓ = 3 modes of spinning binaries differ by up to
1.1e-2 because ``XLALSimInspiralSpinPNMode3m`` takes S1 + S2 where its formula (Arun et al. 2009, with
χ_s = (χ₁ + χ₂)/2, as its own ℓ = 2 function computes it) wants the average: fed half the spins, LALSuite's
ℓ = 3 modes agree with ours to ≤ 9.6e-7 (test below).
"""

import dataclasses

import numpy as np
import pytest
from helpers import needs, reference
from pn_cases import CASES as ALL_CASES

from pnrotor.pn import evolve, lalsuite_orders
from pnrotor.waveform.modes import modes

lal, ls = reference("lal"), reference("lalsimulation")
if ls is not None:
    from pnrotor.interop.lal import polarization_series, sph_harm_time_series, spintaylor_series

pytestmark = needs("lal", "lalsimulation")

DT = 1.0 / 4096
DISTANCE_MPC = 100.0

CASES = {name: ALL_CASES[name] for name in ("equal-nonspinning", "q3-nonspinning", "q3-aligned", "q3-precessing",
                                            "q10-precessing", "near-extremal-precessing", "BNS-precessing")}

MEASURED = {
    # case: {ℓ: max over its modes of |h_ours − h_LAL| / max|h₂₂| (v ≤ 0.4)}, rounded up to two digits; ℓ = 3 of
    # spinning binaries: LALSuite's factor 2 (the second test)
    "equal-nonspinning": {2: 4.7e-7, 3: 4.1e-9, 4: 2.2e-8},
    "q3-nonspinning": {2: 2.5e-7, 3: 2.7e-8, 4: 2.3e-8},
    "q3-aligned": {2: 2.9e-7, 4: 2.8e-8},
    "q3-precessing": {2: 7.8e-6, 4: 2.9e-7},
    "q10-precessing": {2: 4.8e-6, 4: 3.8e-7},
    "near-extremal-precessing": {2: 6.5e-6, 4: 2.4e-7},
    "BNS-precessing": {2: 1.6e-5, 4: 1.4e-7},
}
FACTOR = 4
"""Each ℓ of each case is bounded at FACTOR times its `MEASURED` value.  A change of 0.01% in the 3.5PN flux
coefficient moves the modes by 1.2e-4 to 1.0e-3 of max|h₂₂| (24 times the measurement or more), one of 0.1% in
the 1.5PN spin-orbit terms of H₂₂ by 1.3e-5 to 3.7e-5 where the spins are not small, which fails q3-aligned,
q10-precessing and near-extremal-precessing; a bound of 1e-4 let the latter pass everywhere (and the former
only just failed it)."""


def lal_modes(m1, m2, chi1, chi2, f_min, amplitude_order2=3):
    params = lal.CreateDict()
    ls.SimInspiralWaveformParamsInsertPNAmplitudeOrder(params, amplitude_order2)
    node = ls.SimInspiralChooseTDModes(0.0, DT, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, *chi1, *chi2, f_min, f_min,
                                       DISTANCE_MPC * 1e6 * lal.PC_SI, params, 4, ls.SpinTaylorT4)
    out = {}
    while node is not None:
        out[(node.l, node.m)] = node.mode.data.data.copy()
        node = node.next
    return out


def differences(case, theirs=None):
    """max |h_ours − h_LAL| / max |h₂₂| per mode over v ≤ 0.4 (LAL's modes: ChooseTDModes unless given)."""
    m1, m2, c1, c2, f = CASES[case]
    theirs = lal_modes(m1, m2, c1, c2, f) if theirs is None else theirs
    run = evolve(m1, m2, c1, c2, f, sampling=DT, **lalsuite_orders("T4"))
    ours = modes(run, ell_max=4, amplitude_order=1.5, distance=DISTANCE_MPC)
    n = min(len(run), theirs[(2, 2)].size)
    keep = run.v[:n] <= 0.4
    scale = np.max(np.abs(ours.mode(2, 2)[:n][keep]))
    return {lm: np.max(np.abs(ours.mode(*lm)[:n][keep] - h[:n][keep])) / scale for lm, h in theirs.items()}


@pytest.mark.parametrize("case", list(CASES))
def test_modes_match_lal_spintaylor_t4(case):
    diff = differences(case)
    assert set(diff) == {(ell, m) for ell in range(2, 5) for m in range(-ell, ell + 1)}
    spinning = "nonspinning" not in case
    for ell, measured in MEASURED[case].items():
        worst = max(d for lm, d in diff.items() if lm[0] == ell)
        assert worst < FACTOR * measured, (ell, worst)
    if spinning:   # LALSuite's ℓ = 3 spin terms, twice too large: the next test
        assert max(diff[(3, m)] for m in range(-3, 4)) > 1e-4


def _series(data, like):
    s = lal.CreateREAL8TimeSeries("s", like.epoch, 0.0, like.deltaT, lal.DimensionlessUnit, data.size)
    s.data.data[:] = data
    return s


@pytest.mark.parametrize("case, measured", [("q3-aligned", 3.1e-8), ("q3-precessing", 9.6e-7),
                                            ("near-extremal-precessing", 8.1e-7)])
def test_lal_l3_spin_terms_take_the_sum_of_the_spins_for_their_average(case, measured):
    """LALSuite's own ℓ = 3 formula on its own orbit, with S₁, S₂ halved: then it agrees with our ℓ = 3 modes
    (through their spin terms, which the PN flux confirms); with the spins as ChooseTDModes passes them
    it does not."""
    m1, m2, c1, c2, f = CASES[case]
    V, Phi, *vectors = spintaylor_series(m1, m2, c1, c2, f, "T4", DT)
    spins, frame = vectors[:6], vectors[6:]
    r = DISTANCE_MPC * 1e6 * lal.PC_SI
    for factor, bound in ((0.5, FACTOR * measured), (1.0, None)):
        scaled = [_series(factor * s.data.data, V) for s in spins]
        _, node = ls.SimInspiralSpinPNMode3m(V, Phi, *frame, *scaled, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, r, 3)
        theirs = {}
        while node is not None:
            theirs[(node.l, node.m)] = node.mode.data.data.copy()
            node = node.next
        theirs[(2, 2)] = lal_modes(m1, m2, c1, c2, f)[(2, 2)]
        diff = differences(case, theirs)
        worst = max(diff[(3, m)] for m in range(-3, 4))
        assert worst < bound if bound else worst > 5e-4, (factor, worst)


def test_modes_and_polarizations_go_to_lal_series():
    """pnrotor's modes as LAL's SphHarmTimeSeries hold the same numbers, epoch and Δt; LAL's own sum of them
    (SimInspiralPolarizationsFromSphHarmTimeSeries, azimuth given directly) at azimuth π/2 − φ_ref equals
    pnrotor's h₊, h× for (ι, φ_ref): an independent check of the polarization convention."""
    run = evolve(*ALL_CASES["q3-precessing"], sampling=DT, f_min=15.0)
    m = modes(run, ell_max=4, distance=DISTANCE_MPC)
    hlms = sph_harm_time_series(m)
    assert ls.SphHarmTimeSeriesGetMaxL(hlms) == 4
    for ell, mm in m.ell_m:
        series = ls.SphHarmTimeSeriesGetMode(hlms, ell, mm)
        np.testing.assert_array_equal(series.data.data, m.mode(ell, mm))
        assert series.deltaT == DT and float(series.epoch) == pytest.approx(m.t_seconds[0], abs=1e-9)
    for iota, phi_ref in ((0.7, 0.3), (2.9, 4.0)):
        hp, hc = polarization_series(m, iota, phi_ref)
        lp, lc = ls.SimInspiralPolarizationsFromSphHarmTimeSeries(hlms, iota, np.pi / 2 - phi_ref)
        scale = np.max(np.abs(hp.data.data))
        assert np.max(np.abs(lp.data.data - hp.data.data)) < 1e-14 * scale
        assert np.max(np.abs(lc.data.data - hc.data.data)) < 1e-14 * scale


def test_lal_series_need_strain_and_uniform_samples():
    run = evolve(*ALL_CASES["q3-precessing"], sampling=DT)
    with pytest.raises(ValueError, match="distance"):
        sph_harm_time_series(modes(run, ell_max=2))
    with pytest.raises(ValueError, match="distance"):
        polarization_series(modes(run, ell_max=2), 0.5)
    with pytest.raises(ValueError, match="uniform samples"):
        sph_harm_time_series(modes(evolve(*ALL_CASES["q3-precessing"]), ell_max=2, distance=DISTANCE_MPC))


def test_lal_series_take_long_uniform_runs_with_their_rounding():
    """Times t = k Δt far from t = 0 (a long BNS run; here the grid Δt = 1/4000 s shifted by 5000 s) differ from
    uniform by the rounding of the product, ~1 ulp of t, more than 1e-9 Δt: still uniform, with Δt the sampling
    asked for (every other sample: twice that); a sample off by 1e-6 Δt is not."""
    m = modes(evolve(*ALL_CASES["q3-precessing"], sampling=DT), ell_max=2, distance=DISTANCE_MPC)
    M, dt = m.inputs["M_seconds"], 1.0 / 4000
    t = (np.arange(m.t.size) + 5000 * 4000) * (dt / M) * M
    assert np.max(np.abs(np.diff(t) - dt)) > 1e-9 * dt   # what the check once refused
    inputs = dict(m.inputs, sampling_value=dt)
    shifted = dataclasses.replace(m, t=t / M, t_seconds=t, inputs=inputs)
    assert ls.SphHarmTimeSeriesGetMode(sph_harm_time_series(shifted), 2, 2).deltaT == dt
    assert polarization_series(shifted, 0.5)[0].deltaT == dt
    every_other = dataclasses.replace(shifted, t=shifted.t[::2], t_seconds=t[::2], data=shifted.data[:, ::2],
                                      R=shifted.R[::2], Phi=shifted.Phi[::2])
    assert ls.SphHarmTimeSeriesGetMode(sph_harm_time_series(every_other), 2, 2).deltaT == pytest.approx(2 * dt)
    t[m.t.size // 2] += 1e-6 * dt
    with pytest.raises(ValueError, match="uniform samples"):
        sph_harm_time_series(dataclasses.replace(m, t=t / M, t_seconds=t, inputs=inputs))
