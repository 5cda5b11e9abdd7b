"""Neutron-star tides (issue 33): the 5PN and 6PN tidal terms of Vines, Flanagan & Hinderer 2011 in the energy,
flux and modes, against LALSuite's SpinTaylor with lambda1/lambda2 and against the modes' own flux.

* coefficients: the tidal terms of TaylorT4's v̇ and TaylorT5's dt/dv, re-expanded from the energy and flux by
  pnrotor's truncated-series machinery, equal LALSuite's separately derived ``XLALSimInspiralTaylorT4wdot_1{0,2}PN
  TidalCoeff`` and ``XLALSimInspiralTaylorT2dtdv_1{0,2}PNTidalCoeff`` (LALSimInspiralPNCoefficients.c); the 5PN
  energy term is the Newtonian one of a tidally deformed binary on a circular orbit;
* orbits: ``SimInspiralSpinTaylorPNEvolveOrbit`` with lambda1, lambda2 and tideO = −1 (all) or 10 (5PN only),
  T1/T4/T5, nonprecessing and precessing BNS and NSBH: the same end of the inspiral to a sample, the orbital
  phase and frame within 1e-5 rad, ℓ̂ within 1e-8 rad and the spins within 1e-7 (measured, lalsuite 7.26: ≤ 4.2e-6,
  4.2e-6, 3.1e-9, 2.3e-8, as the point-particle cross-check of tests/test_pn_lal.py, LAL's own integration error
  on ~10⁵ samples), and the tidal dephasing ΔΦ(v) = Φ(Λ) − Φ(0) (2.2–5.0 rad for the BNS from 40 Hz, 0.08–0.20
  rad for the NSBH from 30 Hz) equal to LAL's within 2e-5 rad (measured ≤ 6.7e-6);
* modes: Σ|ḣ_ℓm|² of the tidal amplitudes (pnrotor.waveform.tidal) reproduces the tidal flux at 5PN ((2,2)) and
  6PN ((2,2) and the odd-m modes);
* the options: ``evolve_many``, batch tables, the CLI, HDF5 inputs, ``lalsuite_orders`` and bad input.
"""

import numpy as np
import pytest

from pnrotor.pn import evolve, evolve_many, lalsuite_orders
from pnrotor.pn.energy import tidal_energy
from pnrotor.pn.flux import tidal_flux
from pnrotor.pn.series import kmax_from_orders
from pnrotor.pn.vdot import vdot_series

DT = 1.0 / 4096
LAMBDAS = (350.0, 820.0)


def _tidal_coefficient(series, X1, k, approximant):
    """The coefficient of Λ₁ v^k (Λ₂ = 0) of N (T1, T4) or D (T5) of v̇ = K v⁹ N/D, all orders at LAL's."""
    kmax = kmax_from_orders(3.5, 3.0, 3.0, 6.0)
    with_tides = vdot_series(X1, approximant, kmax, lambda1=1.0)
    without = vdot_series(X1, approximant, kmax)
    return (with_tides[series] - without[series])[k, 0, 0]


@pytest.mark.parametrize("X", [0.5, 0.3, 0.8])
def test_t4_and_t5_tidal_coefficients_are_lals(X):
    """LAL writes the re-expanded tidal terms of dω/dt (T4) and dt/dv (T5) out; ours come from Vines et al.'s energy
    and flux through series.divide to first order in Λ, with the 1PN point-particle cross terms."""
    X4 = X ** 4
    lal_t4 = {10: 6 * X4 * (12 - 11 * X),                                                        # wdot_10PNTidal
              12: X4 * (4421 / 56 - 12263 / 56 * X + 1893 / 4 * X * X - 661 / 2 * X ** 3)}      # wdot_12PNTidal
    lal_t5 = {10: 6 * X4 * (-12 + 11 * X),                                                       # dtdv_10PNTidal
              12: X4 * (-3179 / 8 + 919 / 8 * X + 1143 / 4 * X * X - 65 / 2 * X ** 3)}          # dtdv_12PNTidal
    for k in (10, 12):
        assert _tidal_coefficient(0, X, k, "T4") == pytest.approx(lal_t4[k], rel=1e-13)
        assert _tidal_coefficient(1, X, k, "T5") == pytest.approx(lal_t5[k], rel=1e-13)
    assert _tidal_coefficient(0, X, 10, "T1") == tidal_flux(X)[10]
    assert _tidal_coefficient(1, X, 12, "T1") == 7 * tidal_energy(X)[12]   # E′ ∝ (k + 2)/2 e_k


def test_newtonian_tidal_energy():
    """Body A deformed by B: μΩ²r = μM/r² + 9 λ m_B²/r⁷ (the potential −(3/2) λ m_B²/r⁶ of the induced quadrupole
    Q = −λ E), E = ½μΩ²r² − μM/r − (3/2) λ m_B²/r⁶: the coefficient of Λ_A v¹⁰ in Ê = −2E/(μ v²), v = (MΩ)^⅓,
    solved numerically at small Λ v¹⁰, is tidal_energy's 5PN term."""
    from scipy.optimize import brentq

    for XA in (0.5, 0.3):
        mA, mB, M = XA, 1 - XA, 1.0
        mu, lam, v = mA * mB, 1e4 * XA ** 5, 0.1        # Λ = 10⁴ (Λ v¹⁰ = 10⁻⁶), λ = Λ m_A⁵
        omega = v ** 3
        r = brentq(lambda r: mu * omega ** 2 * r - mu * M / r ** 2 - 9 * lam * mB ** 2 / r ** 7, 1.0, 1e4, xtol=1e-15)
        E = 0.5 * mu * omega ** 2 * r ** 2 - mu * M / r - 1.5 * lam * mB ** 2 / r ** 6
        Ehat = -2 * E / (mu * v ** 2)
        assert (Ehat - 1) / (1e4 * v ** 10) == pytest.approx(tidal_energy(XA)[10], rel=1e-5)


# --------------------------------------------------------------------------------------------------
# LALSuite's SpinTaylor with tides
# --------------------------------------------------------------------------------------------------

CASES = {   # m1, m2, χ₁, χ₂, f_start, (Λ₁, Λ₂)
    "BNS-nonspinning": (1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, LAMBDAS),
    "BNS-precessing": (1.4, 1.3, (0.03, 0.02, 0.03), (0.0, -0.04, 0.01), 40.0, LAMBDAS),
    "NSBH-nonspinning": (8.0, 1.4, (0, 0, 0), (0, 0, 0), 30.0, (0.0, 600.0)),
    "NSBH-aligned": (8.0, 1.4, (0, 0, 0.5), (0, 0, 0), 30.0, (0.0, 600.0)),
    "NSBH-precessing": (8.0, 1.4, (0.5, 0.1, 0.3), (0.0, 0.05, 0.0), 30.0, (0.0, 600.0)),
}


def _angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def _runs(case, approximant, tideO):
    """(LAL's orbit, ours) with and without the tides of ``case``."""
    pytest.importorskip("lalsimulation")
    from pnrotor.interop.lal import spintaylor_orbit

    m1, m2, c1, c2, f, lambdas = CASES[case]
    out = []
    for lam, tide in ((lambdas, tideO), ((0.0, 0.0), 0)):
        L = spintaylor_orbit(m1, m2, c1, c2, f, approximant, DT, lambdas=lam, tideO=tide)
        E = evolve(m1, m2, c1, c2, f, approximant=approximant, sampling=DT, lambda1=lam[0], lambda2=lam[1],
                   **lalsuite_orders(approximant, tideO=tide))
        out.append((L, E))
    return out


def _dephasing(run_tidal, run_point, v):
    """Φ(Λ) − Φ(0) at the same v (each phase interpolated in v, which grows monotonically)."""
    return np.interp(v, run_tidal[0], run_tidal[1]) - np.interp(v, run_point[0], run_point[1])


@pytest.mark.parametrize("approximant,tideO,case", [
    *[(a, t, c) for a in ("T4", "T5") for t in (-1, 10) for c in CASES],
    *[("T1", t, c) for t in (-1, 10) for c in CASES if "precessing" not in c and "aligned" not in c],
])
def test_orbit_and_tidal_dephasing_are_lals(approximant, tideO, case):
    """T1 only without spins: with spins LAL's T1 differs by its 3PN QM flux coefficient (tests/test_pn_lal.py)."""
    (L, E), (L0, E0) = _runs(case, approximant, tideO)
    assert abs(len(E) - L["v"].size) <= 1 and abs(len(E0) - L0["v"].size) <= 1
    N = min(len(E), L["v"].size)
    lh = L["ell"][:N] / np.linalg.norm(L["ell"][:N], axis=1)[:, None]
    nL = np.cos(L["Phi"][:N])[:, None] * L["e1"][:N] + np.sin(L["Phi"][:N])[:, None] * np.cross(lh, L["e1"][:N])
    assert np.max(np.abs(E.Phi[:N] - L["Phi"][:N])) < 1e-5
    assert np.max(_angle(E.n_hat[:N], nL)) < 1e-5
    assert np.max(_angle(E.ell_hat[:N], lh)) < 1e-8
    assert max(np.max(np.abs(E.chi1[:N] - L["chi1"][:N])), np.max(np.abs(E.chi2[:N] - L["chi2"][:N]))) < 1e-7
    v = np.linspace(E.v[0], min(E.v[-1], L["v"][-1]), 2000)
    ours, lals = _dephasing((E.v, E.Phi), (E0.v, E0.Phi), v), _dephasing((L["v"], L["Phi"]), (L0["v"], L0["Phi"]), v)
    assert np.max(np.abs(lals)) > 0.05                           # the tides are no small correction here
    assert np.max(np.abs(ours - lals)) < 2e-5


def test_tidal_order_5_and_6_and_none():
    """tidal_order 0 is the point-particle run bitwise; 5 and 6 differ from it and from each other."""
    kw = dict(sampling="final", f_max=400.0)
    point = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, **kw)
    none = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, lambda1=350.0, lambda2=820.0, tidal_order=0, **kw)
    five = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, lambda1=350.0, lambda2=820.0, tidal_order=5, **kw)
    six = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, lambda1=350.0, lambda2=820.0, **kw)
    assert none.t[-1] == point.t[-1] and none.Phi[-1] == point.Phi[-1]
    assert point.Phi[-1] - five.Phi[-1] > 0.1 and five.Phi[-1] - six.Phi[-1] > 0.01
    assert six.inputs["tidal_order"] == 6.0 and six.inputs["lambda2"] == 820.0


# --------------------------------------------------------------------------------------------------
# modes
# --------------------------------------------------------------------------------------------------

def test_tidal_modes_carry_the_tidal_flux():
    """The tidal flux (Vines et al. 2011) at 5PN from the (2,2) amplitude, at 5.5PN nothing, at 6PN from (2,2) with its
    1PN point-particle term and the odd-m modes (2,1), (3,1), (3,3): coefficient by coefficient, linear in Λᵢ."""
    from test_waveform_amplitudes import mode_flux_series

    for m1, m2 in ((1.4, 1.3), (8.0, 1.4), (1.0, 1.0)):
        X1 = m1 / (m1 + m2)
        for lambdas in ((350.0, 820.0), (0.0, 600.0), (400.0, 0.0)):
            f = mode_flux_series(m1, m2, 12, tides=(*lambdas, 12))[0] - mode_flux_series(m1, m2, 12)[0]
            for k in (10, 12):
                expected = lambdas[0] * tidal_flux(X1)[k] + lambdas[1] * tidal_flux(1 - X1)[k]
                assert f[k] == pytest.approx(expected, rel=1e-12)
            assert f[11] == 0.0 and not f[:10].any()


def test_modes_take_the_runs_tides():
    from pnrotor.waveform.modes import modes

    run = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 300.0, sampling=DT, lambda1=350.0, lambda2=820.0)
    h, h0 = modes(run, 4), modes(run, 4, tidal_order=0)
    row = h.ell_m.index((2, 2))
    v = run.v
    X1 = 1.4 / 2.7
    lead = 350.0 * 3 * X1 ** 4 * (3 - 2 * X1) + 820.0 * 3 * (1 - X1) ** 4 * (1 + 2 * X1)
    ratio = np.abs(h.data[row]) / np.abs(h0.data[row]) - 1
    assert ratio[0] == pytest.approx(lead * v[0] ** 10, rel=0.2)      # the 6PN term and products: ~10% at 300 Hz
    assert h.inputs["tidal_amplitude_order"] == 6.0 and "tidal_amplitude_order" not in h0.inputs
    odd = h.ell_m.index((2, 1))
    assert np.all(np.abs(h.data[odd]) > np.abs(h0.data[odd]))
    five = modes(run, 4, tidal_order=5)
    np.testing.assert_array_equal(five.data[odd], h0.data[odd])   # the odd-m terms are v¹¹: 5.5PN
    assert np.all(np.abs(five.data[row]) != np.abs(h.data[row]))
    with pytest.raises(ValueError, match="tidal_order must be 0"):
        modes(run, 4, tidal_order=4)


# --------------------------------------------------------------------------------------------------
# the options everywhere
# --------------------------------------------------------------------------------------------------

def test_evolve_many_with_tides_equals_evolve():
    m1 = np.array([1.4, 1.6, 8.0, 1.3])
    m2 = np.array([1.3, 1.2, 1.4, 1.3])
    c1 = np.array([[0, 0, 0], [0.02, 0, 0.03], [0, 0, 0.5], [0, 0, 0]], dtype=float)
    c2 = np.zeros((4, 3))
    l1, l2 = np.array([350.0, 200.0, 0.0, 0.0]), np.array([820.0, 900.0, 600.0, 0.0])
    for tidal_order in (None, 5):
        pop = evolve_many(m1, m2, c1, c2, 60.0, lambda1=l1, lambda2=l2, tidal_order=tidal_order)
        for i in range(4):
            e = evolve(m1[i], m2[i], c1[i], c2[i], 60.0, sampling="final", lambda1=l1[i], lambda2=l2[i],
                       tidal_order=tidal_order)
            assert pop.t[i] == e.t[-1] and pop.Phi[i] == e.Phi[-1] and pop.termination[i] == e.termination
            np.testing.assert_array_equal(pop.R[i], e.R[-1])
    bad = evolve_many(m1, m2, c1, c2, 60.0, lambda1=[350.0, -1.0, 0.0, np.nan])
    assert list(bad.termination[[1, 3]]) == ["invalid", "invalid"] and "lambda1 must be a finite number >= 0" in \
        bad.message[1]


@pytest.mark.parametrize("kw,message", [
    (dict(lambda1=-1.0), "lambda1 must be a finite number >= 0"),
    (dict(lambda2=float("inf")), "lambda2 must be a finite number >= 0"),
    (dict(lambda1="350"), "lambda1 must be a finite number >= 0"),
    (dict(tidal_order=4), "tidal_order must be 0 (no tides), 5 or 6"),
    (dict(tidal_order=True), "tidal_order must be 0 (no tides), 5 or 6"),
])
def test_bad_tidal_input(kw, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 40.0, **kw)


def test_lalsuite_orders_maps_tideO():
    assert [lalsuite_orders("T4", tideO=t)["tidal_order"] for t in (-1, 12, 10, 0)] == [6.0, 6.0, 5.0, 0.0]
    assert lalsuite_orders("T4")["tidal_order"] == 6.0          # LAL's default, all
    with pytest.raises(ValueError, match="tideO"):
        lalsuite_orders("T4", tideO=5)


def test_cli_batch_and_hdf5_carry_the_deformabilities(tmp_path, capsys):
    from pnrotor import hdf5
    from pnrotor.cli import main

    args = ["evolve", "--m1", "1.4", "--m2", "1.3", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "300",
            "--lambda1", "350", "--lambda2", "820", "--tidal-order", "5", "-o", str(tmp_path / "one.h5")]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "tides lambda1 350, lambda2 820 to 5PN" in out
    stored = hdf5.read(tmp_path / "one.h5")
    direct = evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 300.0, lambda1=350.0, lambda2=820.0, tidal_order=5)
    assert (stored.inputs["lambda1"], stored.inputs["lambda2"], stored.inputs["tidal_order"]) == (350.0, 820.0, 5.0)
    np.testing.assert_array_equal(stored.Phi, direct.Phi)

    (tmp_path / "b.csv").write_text('m1,m2,chi1,chi2,f_ref,lambda1,lambda2,sampling\n'
                                    '1.4,1.3,"0,0,0","0,0,0",300,350,820,final\n'
                                    '1.4,1.3,"0,0,0","0,0,0",300,,,final\n')
    assert main(["evolve", "--batch", str(tmp_path / "b.csv"), "--jobs", "1", "-o", str(tmp_path / "b.h5")]) == 0
    capsys.readouterr()
    names = ["T4_m1.4_m1.3_chi1-0,0,0_chi2-0,0,0_f300_lambda1-350_lambda2-820_final",
             "T4_m1.4_m1.3_chi1-0,0,0_chi2-0,0,0_f300_final"]
    tidal, point = (hdf5.read(tmp_path / "b.h5", name) for name in names)
    assert tidal.Phi[-1] == evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 300.0, sampling="final", **dict(
        zip(("lambda1", "lambda2"), LAMBDAS))).Phi[-1]
    assert point.inputs["lambda1"] == 0.0 and tidal.Phi[-1] != point.Phi[-1]

    assert main(args[:-2] + ["--lambda1", "-3", "-o", str(tmp_path / "bad.h5")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pnrotor evolve: error: lambda1 must be a finite number >= 0") and err.count("\n") == 1
    assert not (tmp_path / "bad.h5").exists()
