"""pnrotor's PyCBC plugin through PyCBC's public entry points, against LAL's SpinTaylorT4 through the same calls.

Reference: ``pycbc.waveform.get_td_waveform(approximant="SpinTaylorT4", …)`` with the same keywords (LAL's
ChooseTDWaveform).  Both at ``spin_order=6`` (LAL's SpinTaylorT4 truncation; pnrotor's default also has the 3.5PN
and 4PN spin-orbit terms of v̇).  Goals (issue 31): match ≥ 0.99999 (aLIGO zero-detuned high-power PSD, from
f_lower) and h₊, h× within 1e-4 of max|h| sample by sample, at amplitude order 0.  Measured: ≤ 2.4e-6 of max|h|
sample by sample (BNS; ≤ 1e-6 for BBH and NSBH: the integrators' difference), 1 − match ≤ 3e-12, at amplitude
order 0 and at LAL's highest (1.5PN, ``amplitude_order=3``, where pnrotor's default ℓ ≤ 5 are all the modes of that
order).  LAL's series have
one sample more at the start (below f_lower); the comparison is on the common samples, aligned by the epochs.

Cost: ~15 s on an idle 2-core machine, most of it importing PyCBC (here and in the fresh process).
"""

import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("lalsimulation")
waveform = pytest.importorskip("pycbc.waveform")

from pycbc.filter import match  # noqa: E402
from pycbc.psd import aLIGOZeroDetHighPower  # noqa: E402
from pycbc.types import FrequencySeries, TimeSeries  # noqa: E402
from pycbc.waveform.waveform import FailedWaveformError  # noqa: E402

from pipeline_cases import CASES, DT, pycbc_keywords as keywords  # noqa: E402


def common(ours, theirs):
    """The samples of ``theirs`` at the times of ``ours`` (LAL's start one sample earlier), checking that both end at
    the same sample (t = 0)."""
    offset = round((float(ours.start_time) - float(theirs.start_time)) / DT)
    assert offset in (0, 1) and len(theirs) - offset == len(ours), (offset, len(theirs), len(ours))
    return theirs.numpy()[offset:]


def differences(case, **extra):
    """max |h_ours − h_LAL| / max |h_LAL| for h₊, h×, and 1 − match of h₊, h×."""
    kw = keywords(case, **extra)
    ours = waveform.get_td_waveform(approximant="PNRotorT4", **kw)
    theirs = waveform.get_td_waveform(approximant="SpinTaylorT4", **kw)
    n = 2 ** int(np.ceil(np.log2(len(ours[0]))))
    psd = aLIGOZeroDetHighPower(n // 2 + 1, 1.0 / (n * DT), kw["f_lower"])
    out = []
    for a, b in zip(ours, theirs):
        assert isinstance(a, TimeSeries) and a.delta_t == DT
        b = common(a, b)
        out.append(np.max(np.abs(a.numpy() - b)) / np.max(np.abs(b)))
        padded = [TimeSeries(np.concatenate([x, np.zeros(n - len(x))]), delta_t=DT) for x in (a.numpy(), b)]
        out.append(1.0 - match(*padded, psd=psd, low_frequency_cutoff=kw["f_lower"])[0])
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_matches_spintaylor_t4_at_amplitude_order_0(case):
    dp, mp, dc, mc = differences(case, amplitude_order=0)
    assert max(dp, dc) < 1e-4, (dp, dc)
    assert max(mp, mc) < 1e-5, (mp, mc)


@pytest.mark.parametrize("case", ["BBH-precessing", "NSBH-precessing"])
def test_matches_spintaylor_t4_at_its_highest_amplitude_order(case):
    """LAL's SpinTaylor polarizations go to 1.5PN (its amplitude_order -1 is 3); pnrotor's at 1.5PN (ℓ ≤ 5 by
    default) agree with them as closely as at amplitude order 0."""
    dp, mp, dc, mc = differences(case, amplitude_order=3)
    assert max(dp, dc) < 1e-4, (dp, dc)
    assert max(mp, mc) < 1e-5, (mp, mc)


@pytest.mark.parametrize("tidal_order", [10, 0])
def test_tidal_order_is_lals_tide_o(tidal_order):
    """LAL's tideO: 10 keeps the 5PN tidal terms alone, 0 none (−1, all, in the cases above); against SpinTaylorT4
    with the same tidal_order, each far from the waveform with all the tidal terms."""
    dp, mp, dc, mc = differences("BNS-tidal", amplitude_order=0, tidal_order=tidal_order)
    assert max(dp, dc) < 1e-4, (dp, dc)
    assert max(mp, mc) < 1e-5, (mp, mc)
    kw = keywords("BNS-tidal", amplitude_order=0)
    given, every = (waveform.get_td_waveform(approximant="PNRotorT4", **kw, tidal_order=k)[0].numpy() for k in
                    (tidal_order, -1))
    n = min(len(given), len(every))
    assert np.max(np.abs(given[-n:] - every[-n:])) > 1e-2 * np.max(np.abs(every))


def test_dquad_mon_is_lals_quadparam_minus_1():
    """LAL's SpinTaylor evolves with quadparam = 1 + dQuadMon (its ChooseTDWaveform refuses dQuadMon for them, as a
    testing-GR parameter): PyCBC's dquad_mon1,2 are pnrotor's κ₁,₂ − 1 (κ checked against LAL's orbit in
    tests/test_pn_lal.py)."""
    kw = keywords("BBH-precessing", amplitude_order=0)
    dquad, kappa, bh = (waveform.get_td_waveform(approximant="PNRotorT4", **kw, **extra)[0].numpy()
                        for extra in ({"dquad_mon1": 2.0, "dquad_mon2": 1.0}, {"kappa1": 3.0, "kappa2": 2.0}, {}))
    assert np.array_equal(dquad, kappa) and not np.array_equal(dquad[-len(bh):], bh)


def test_highest_amplitude_orders_differ_by_pnrotors_2pn_to_35pn_terms():
    """At each code's highest amplitude order (pnrotor 3.5PN with ℓ ≤ 8, LAL 1.5PN) the polarizations differ by
    several percent of the peak; the difference is pnrotor's terms beyond 1.5PN: pnrotor's own 3.5PN − 1.5PN
    difference reproduces it to 1e-6 of the peak."""
    kw = keywords("BBH-precessing")
    highest = waveform.get_td_waveform(approximant="PNRotorT4", amplitude_order=-1, **kw)[0]
    lal_highest = common(highest, waveform.get_td_waveform(approximant="SpinTaylorT4", amplitude_order=-1, **kw)[0])
    ours_15 = waveform.get_td_waveform(approximant="PNRotorT4", amplitude_order=3, **kw)[0].numpy()
    peak = np.max(np.abs(lal_highest))
    difference = np.max(np.abs(highest.numpy() - lal_highest)) / peak
    assert difference > 1e-2
    assert np.max(np.abs((highest.numpy() - lal_highest) - (highest.numpy() - ours_15))) / peak < 1e-6


def test_default_ell_max_has_every_mode_of_the_amplitude_order():
    """ℓ enters the amplitude at (ℓ − 2)/2 PN: at 1.5PN the default ℓ ≤ 5 gives what ℓ ≤ 8 gives, ℓ ≤ 4 does not."""
    kw = keywords("BBH-precessing", amplitude_order=3)
    default, ell8, ell4 = (waveform.get_td_waveform(approximant="PNRotorT4", **kw, **extra)[0].numpy()
                           for extra in ({}, {"ell_max": 8}, {"ell_max": 4}))
    peak = np.max(np.abs(ell8))
    assert np.max(np.abs(default - ell8)) < 1e-14 * peak
    assert np.max(np.abs(ell4 - ell8)) > 1e-3 * peak


def test_f_ref_0_means_f_lower():
    kw = keywords("BBH-precessing", amplitude_order=0)
    zero = waveform.get_td_waveform(approximant="PNRotorT4", **dict(kw, f_ref=0.0))[0]
    lower = waveform.get_td_waveform(approximant="PNRotorT4", **dict(kw, f_ref=kw["f_lower"]))[0]
    later = waveform.get_td_waveform(approximant="PNRotorT4", **kw)[0]
    assert np.array_equal(zero.numpy(), lower.numpy()) and float(zero.start_time) == float(lower.start_time)
    assert not np.array_equal(zero.numpy()[-len(later):], later.numpy())


def test_frequency_domain_matches_spintaylor_t5_through_pycbc():
    """PyCBC's own route from the time domain (length and end-frequency estimators): PNRotorT5 against LAL's
    SpinTaylorT5 through the same get_fd_waveform (which PyCBC gives SpinTaylorT5 natively, sampled at 1/2048 s:
    this BBH's harmonics end below 1024 Hz, so pnrotor's end-frequency estimate asks for that sampling too)."""
    kw = dict(keywords("BBH-precessing", amplitude_order=0), delta_f=1.0 / 16)
    ours = waveform.get_fd_waveform(approximant="PNRotorT5", **kw)
    theirs = waveform.get_fd_waveform(approximant="SpinTaylorT5", **kw)
    assert waveform.get_waveform_end_frequency(approximant="PNRotorT5", **kw) == 1024.0
    assert isinstance(ours[0], FrequencySeries) and ours[0].delta_f == kw["delta_f"] and len(ours[0]) == len(theirs[0])
    psd = aLIGOZeroDetHighPower(len(ours[0]), kw["delta_f"], kw["f_lower"])
    for a, b in zip(ours, theirs):
        assert match(a, b, psd=psd, low_frequency_cutoff=kw["f_lower"])[0] > 1 - 1e-5


@pytest.mark.parametrize("amplitude_order, harmonic", [(0, 1), (-1, 4)])
def test_end_frequency_is_the_highest_harmonic_at_lals_end_of_the_inspiral(amplitude_order, harmonic):
    """A BNS ends above 1 kHz: the estimate is (ℓ_max / 2) × the GW frequency at the end of LAL's own orbit
    evolution (SimInspiralSpinTaylorPNEvolveOrbit, an independent integration of the same model; from 1 kHz,
    sampled finely enough that its last sample is at the end)."""
    from pnrotor.interop.lal import spintaylor_orbit

    m1, m2, c1, c2, *_ = CASES["BNS-nonspinning"]
    v_end = spintaylor_orbit(m1, m2, c1, c2, 1000.0, "T4", 1e-7)["v"][-1]
    lal_end = v_end ** 3 / (np.pi * (m1 + m2) * 4.925490947641267e-06)   # M☉ in s (LAL_MTSUN_SI)
    f_end = waveform.get_waveform_end_frequency(approximant="PNRotorT4",
                                                **keywords("BNS-nonspinning", amplitude_order=amplitude_order))
    assert f_end == pytest.approx(harmonic * lal_end, rel=1e-2) and f_end > 1024   # LAL stops up to a step later


def test_plugin_after_a_plain_import_in_a_fresh_process():
    """Only ``import pycbc.waveform``: PyCBC finds the entry points; get_td_waveform stays pnrotor's time-domain
    function (a length estimator re-runs PyCBC's td/fd transform) and get_fd_waveform works."""
    code = """
import pycbc.waveform as w
kw = dict(mass1=30, mass2=10, spin1x=0.5, spin2y=0.4, delta_t=1/4096, f_lower=20, f_ref=25, inclination=0.7,
          coa_phase=0.4, distance=100, amplitude_order=0)
for name in ("PNRotorT1", "PNRotorT4", "PNRotorT5"):
    assert name in w.td_approximants() and name in w.fd_approximants(), name
    hp, hc = w.get_td_waveform(approximant=name, **kw)
    print(name, type(hp).__name__, len(hp), float(hp.start_time), hp[100])
fp, fc = w.get_fd_waveform(approximant="PNRotorT4", delta_f=1/16, **kw)
print(type(fp).__name__, fp.delta_f, len(fp))
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.split("\n")
    kw = dict(mass1=30, mass2=10, spin1x=0.5, spin2y=0.4, delta_t=DT, f_lower=20, f_ref=25, inclination=0.7,
              coa_phase=0.4, distance=100, amplitude_order=0)
    for line, name in zip(lines, ("PNRotorT1", "PNRotorT4", "PNRotorT5")):
        hp = waveform.get_td_waveform(approximant=name, **kw)[0]
        assert line == f"{name} TimeSeries {len(hp)} {float(hp.start_time)} {hp[100]}"
    assert lines[3].startswith("FrequencySeries 0.0625 ")


BAD = {   # keyword changes → what pnrotor's message names
    "negative mass": ({"mass1": -30.0}, "m1 must be a finite positive mass"),
    "spin above 1": ({"spin1z": 1.2}, "|chi1| = 1.30384"),
    "f_lower past the end": ({"f_lower": 400.0, "f_ref": 0.0}, "past the end of the T4 inspiral"),
    "f_ref past the end": ({"f_ref": 400.0}, "past the end of the T4 inspiral"),
    "f_ref below f_lower": ({"f_ref": 15.0}, "must not be below f_lower"),
    "nan mass": ({"mass2": float("nan")}, "m2 must be a finite positive mass"),
    "infinite spin": ({"spin2x": float("inf")}, "chi2 must be finite"),
    "nan inclination": ({"inclination": float("nan")}, "inclination must be a finite angle"),
    "amplitude order": ({"amplitude_order": 9}, "amplitude_order must be -1"),
    "eccentricity": ({"eccentricity": 0.1}, "eccentricity = 0.1: PNRotorT4 does not model it"),
    "negative deformability": ({"lambda1": -400.0}, "lambda1 must be a finite number >= 0"),
    "nan deformability": ({"lambda2": float("nan")}, "lambda2 must be a finite number >= 0"),
    "tidal order": ({"tidal_order": 13}, "tidal_order must be -1 (all: 5PN and 6PN), 12 (6PN), 10 (5PN) or 0"),
    "octupolar tides": ({"lambda_octu1": 100.0}, "lambda_octu1 = 100.0: PNRotorT4 does not model it"),
    "testing GR": ({"dchi2": 0.1}, "dchi2 = 0.1"),
    "mode array": ({"mode_array": [(2, 2)]}, "mode_array = [(2, 2)]: PNRotorT4 does not model it"),
    "frame axis J": ({"frame_axis": 1}, "frame_axis = 1"),
    "unknown keyword": ({"ellmax": 3}, "unknown keyword 'ellmax'"),
    "two names for one order": ({"phase_order": 7, "pn_order": 3.5}, "give either phase_order or pnrotor's pn_order"),
}


@pytest.mark.parametrize("bad", list(BAD))
def test_bad_input_is_pycbcs_failed_waveform_error_with_pnrotors_message(bad):
    """Through get_td_waveform and get_fd_waveform (but for f_ref, which PyCBC's frequency-domain route replaces by
    f_lower)."""
    change, message = BAD[bad]
    kw = dict(keywords("BBH-precessing", amplitude_order=0), **change)
    calls = [(waveform.get_td_waveform, {})]
    if "f_ref" not in change:
        calls.append((waveform.get_fd_waveform, {"delta_f": 1.0 / 16}))
    for call, extra in calls:
        with pytest.raises(FailedWaveformError, match=r"^PNRotorT4: ") as raised:
            call(approximant="PNRotorT4", **kw, **extra)
        assert message in str(raised.value) and raised.value.__suppress_context__
