"""pnrotor.waveform.modes: inertial modes from the evolved frame, their symmetries, frames, rotation
covariance, units and polarizations."""

import numpy as np
import pytest

import pnrotor
from pnrotor import quaternion as q
from pnrotor.waveform.amplitudes import coorbital_modes
from pnrotor.waveform.layout import ell_m, mode_index
from pnrotor.waveform.modes import Modes, modes
from pnrotor.waveform.wigner import wigner_D

PRECESSING = dict(m1=30.0, m2=10.0, chi1=(0.5, 0.1, 0.3), chi2=(0.0, 0.4, -0.2), f_ref=40.0)
DT = 1.0 / 4096


def test_nonprecessing_modes_are_amplitudes_times_exp_minus_i_m_phi():
    for chi in ((0.0, 0.0, 0.0), (0.0, 0.0, 0.6)):
        run = pnrotor.evolve(30.0, 10.0, chi, chi, 30.0, sampling=DT)
        h = modes(run)
        chi_orbit = None if not any(chi) else np.tile(chi, (len(run), 1))
        H = coorbital_modes(run.v, chi_orbit, chi_orbit, 30.0, 10.0, 8, 7)
        scale = np.abs(h.mode(2, 2)).max()
        for ell, m in h.ell_m:
            np.testing.assert_allclose(h.mode(ell, m), H[mode_index(ell, m)] * np.exp(-1j * m * run.Phi),
                                       rtol=0, atol=1e-12 * scale)
            np.testing.assert_allclose(h.mode(ell, -m), (-1) ** ell * np.conj(h.mode(ell, m)), rtol=0,
                                       atol=1e-12 * scale)


def test_aligned_run_in_a_tilted_frame_takes_the_general_rotation():
    """The nonprecessing shortcut h = 𝔇(R₀)(H e^{−imΦ}) equals 𝔇(R) H with the run's own rotors."""
    from pnrotor.waveform.wigner import rotate_modes
    ell = np.array([0.3, -0.4, np.sqrt(0.75)])
    n = np.cross(ell, [0.0, 1.0, 0.0])
    n /= np.linalg.norm(n)
    run = pnrotor.evolve(30.0, 10.0, 0.5 * ell, -0.3 * ell, 30.0, ell_hat=ell, n_hat=n, sampling=DT)
    assert run.inputs["state"] == "aligned"
    h = modes(run, ell_max=4)
    chi1 = q.rotate(q.conjugate(run.R), run.chi1)
    chi2 = q.rotate(q.conjugate(run.R), run.chi2)
    direct = rotate_modes(coorbital_modes(run.v, chi1, chi2, 30.0, 10.0, 4, 7), run.R, 4)
    assert np.max(np.abs(h.data - direct)) < 1e-12 * np.abs(direct).max()


def test_one_pass_equals_amplitudes_then_rotation():
    """modes() forms H block by block inside the rotation and skips the columns m' without terms (ℓ ≥ 5 has no
    m' = 0, ℓ = 8 only even m'): the same as the whole H array rotated with every column."""
    from pnrotor.waveform.wigner import rotate_modes
    run = pnrotor.evolve(**PRECESSING, sampling="steps")
    h = modes(run)
    direct = rotate_modes(coorbital_modes(run.v, run.chi1, run.chi2, 30.0, 10.0, 8, 7, R=run.R), run.R, 8)
    assert np.max(np.abs(h.data - direct)) < 1e-13 * np.abs(direct).max()


def test_equal_mass_nonspinning_has_only_the_even_m_modes_the_amplitudes_allow():
    from pnrotor.waveform import nonspinning
    allowed = {(ell, s * m) for (ell, m) in nonspinning.terms(0.25, 0.0) for s in (1, -1) if m % 2 == 0}
    h = modes(pnrotor.evolve(20.0, 20.0, (0, 0, 0), (0, 0, 0), 30.0, sampling="steps"))
    nonzero = {(ell, m) for ell, m in h.ell_m if np.max(np.abs(h.mode(ell, m))) > 0}
    assert nonzero == allowed and (3, 0) in nonzero and (2, 1) not in nonzero


def test_rotating_the_binary_rotates_its_modes():
    """ℓ̂, n̂ and spins rotated by a fixed rotor Q: the modes become 𝔇(Q) h, the evolution being the same
    in the rotated frame (to the integrator's tolerance)."""
    Q = q.normalize(np.array([0.3, -0.5, 0.7, 0.2]))
    run = pnrotor.evolve(**PRECESSING, sampling=DT, atol=1e-13)
    ell, n = q.rotate(Q, np.array([0.0, 0.0, 1.0])), q.rotate(Q, np.array([1.0, 0.0, 0.0]))
    chi1, chi2 = q.rotate(Q, np.array(PRECESSING["chi1"])), q.rotate(Q, np.array(PRECESSING["chi2"]))
    turned = pnrotor.evolve(**dict(PRECESSING, chi1=chi1, chi2=chi2), ell_hat=ell, n_hat=n, sampling=DT, atol=1e-13)
    h, h_turned = modes(run), modes(turned)
    N = min(len(run), len(turned))
    expected = wigner_D(Q, 8) @ h.data[:, :N]
    scale = np.abs(h.mode(2, 2)).max()
    assert np.max(np.abs(h_turned.data[:, :N] - expected)) < 1e-8 * scale


def test_frames_round_trip_and_coorbital_is_the_amplitudes():
    run = pnrotor.evolve(**PRECESSING, sampling="steps")
    h = modes(run, ell_max=4, amplitude_order=2)
    co = h.in_frame("coorbital")
    chi1 = q.rotate(q.conjugate(run.R), run.chi1)
    chi2 = q.rotate(q.conjugate(run.R), run.chi2)
    H = coorbital_modes(run.v, chi1, chi2, 30.0, 10.0, 4, 4)
    scale = np.abs(H).max()
    assert np.max(np.abs(co.data - H)) < 1e-13 * scale
    for frame in ("coprecessing", "coorbital"):
        back = h.in_frame(frame).in_frame("inertial")
        assert np.max(np.abs(back.data - h.data)) < 1e-13 * scale
    cp = h.in_frame("coprecessing").data            # coprecessing = coorbital turned back by Φ about ẑ
    for ell, m in h.ell_m:
        np.testing.assert_allclose(cp[mode_index(ell, m)], co.data[mode_index(ell, m)] * np.exp(-1j * m * run.Phi),
                                   rtol=0, atol=1e-13 * scale)


def test_polarizations_are_the_quadrupole_formula_at_leading_order():
    """ℓ = 2, Newtonian amplitude, nonspinning: h₊ = (M/D) 2ν v² (1 + cos²ι) cos 2(Φ − φ),
    h× = (M/D) 4ν v² cos ι sin 2(Φ − φ), seen from φ = π/2 − φ_ref."""
    astropy_units = pytest.importorskip("astropy.units")
    from astropy import constants
    run = pnrotor.evolve(30.0, 10.0, (0, 0, 0), (0, 0, 0), 30.0, sampling=DT)
    h = modes(run, ell_max=2, amplitude_order=0)
    nu, v, D = 0.1875, run.v, 400.0
    M_over_D = run.inputs["M_seconds"] * constants.c.value / (D * astropy_units.Mpc.to(astropy_units.m))
    for iota, phi_ref in ((0.3, 0.0), (1.2, 0.7), (np.pi, 2.0)):
        hp, hc = h.polarizations(iota, phi_ref, distance=D)
        x = 2 * (run.Phi - (np.pi / 2 - phi_ref))
        np.testing.assert_allclose(hp, M_over_D * 2 * nu * v ** 2 * (1 + np.cos(iota) ** 2) * np.cos(x),
                                   rtol=0, atol=1e-12 * M_over_D)
        np.testing.assert_allclose(hc, M_over_D * 4 * nu * v ** 2 * np.cos(iota) * np.sin(x),
                                   rtol=0, atol=1e-12 * M_over_D)
    strain = modes(run, ell_max=2, amplitude_order=0, distance=D * astropy_units.Mpc)
    np.testing.assert_allclose(strain.data, M_over_D * h.data, rtol=1e-14)
    hp2, _ = strain.polarizations(0.3, 0.0, distance=2 * D)
    np.testing.assert_allclose(hp2, 0.5 * h.polarizations(0.3, 0.0, distance=D)[0], rtol=1e-14)


@pytest.mark.parametrize("kw, message", [
    (dict(ell_max=9), "ell_max"), (dict(ell_max=1), "ell_max"), (dict(ell_max=True), "ell_max"),
    (dict(amplitude_order=0.25), "amplitude_order"), (dict(amplitude_order=4.5), "amplitude_order"),
    (dict(amplitude_order="x"), "amplitude_order"), (dict(amplitude_order="1.5"), "amplitude_order"),
    (dict(amplitude_order=b"1"), "amplitude_order"), (dict(amplitude_order=np.True_), "amplitude_order"),
    (dict(amplitude_order=True), "amplitude_order"), (dict(distance=-1.0), "distance"),
    (dict(distance=float("nan")), "distance"),
    # a review of 2026-11-28: an OverflowError, text taken as a number, modes scaled to 0 (1e300 Mpc is inf metres)
    (dict(amplitude_order=10 ** 400), "amplitude_order"), (dict(distance="100"), "distance"),
    (dict(distance=b"1"), "distance"), (dict(distance=1e300), "distance = 1e\\+300 Mpc is out of range"),
])
def test_bad_arguments_name_themselves(kw, message):
    run = pnrotor.evolve(30.0, 10.0, (0, 0, 0), (0, 0, 0), 100.0, sampling="final")
    with pytest.raises(ValueError, match=message):
        modes(run, **kw)


def test_modes_take_an_evolution():
    """What is not an Evolution (a Modes, a file's name, None) is a TypeError saying what modes() takes, not an
    AttributeError from inside."""
    h = modes(pnrotor.evolve(30.0, 10.0, (0, 0, 0), (0, 0, 0), 100.0, sampling="final"), ell_max=2)
    for wrong in (h, "run.h5", None):
        with pytest.raises(TypeError, match="modes\\(\\) takes an Evolution"):
            modes(wrong)


def test_modes_and_their_rotation_are_bounded_by_memory_before_allocating(monkeypatch):
    """Modes that would not fit (only 1 MiB free, as pretended here): a ValueError naming ell_max and sampling with
    the size, from modes() and from Modes.in_frame, before either allocates; with the memory there they are computed."""
    from pnrotor import processes
    run = pnrotor.evolve(**PRECESSING, sampling=DT)
    need = 16 * 77 * len(run)   # ℓ ≤ 8: 77 complex rows
    h = modes(run, ell_max=8)
    monkeypatch.setattr(processes, "available_memory", lambda: need)
    with pytest.raises(ValueError, match=f"modes\\(\\): 77 modes of {len(run)} samples would need .* GiB, more than "
                                         ".*; choose a smaller ell_max or a coarser sampling"):
        modes(run, ell_max=8)
    with pytest.raises(ValueError, match=f"rotating them: 77 modes of {len(run)} samples"):
        h.in_frame("coprecessing")
    monkeypatch.setattr(processes, "available_memory", lambda: need + 1)
    assert modes(run, ell_max=8).data.shape == (77, len(run))


def test_available_memory_sees_the_address_space_limit():
    """``ulimit -v`` (RLIMIT_AS) set in a fresh process to its current size + 64 MiB: available_memory() is at most
    64 MiB there, and an evolve whose samples need more is refused with the sampling's ValueError, not a MemoryError
    (they would fit in the machine's free memory)."""
    import subprocess
    import sys
    code = """
import resource
import pnrotor
from pnrotor.processes import available_memory
pnrotor.evolve(1.4, 1.4, (0, 0, 0), (0, 0, 0), 300.0, sampling=1 / 65536)   # compiled (or loaded) before the limit
with open("/proc/self/statm") as f:
    size = int(f.read().split()[0]) * resource.getpagesize()
resource.setrlimit(resource.RLIMIT_AS, (size + 64 * 2 ** 20, resource.RLIM_INFINITY))
assert 0 < available_memory() <= 64 * 2 ** 20, available_memory()
try:
    pnrotor.evolve(1.4, 1.4, (0, 0, 0), (0, 0, 0), 30.0, sampling=1 / 65536)
except ValueError as e:
    print("refused:", e)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "refused: sampling = " in out.stdout and "more than" in out.stdout


def test_modes_object():
    h = modes(pnrotor.evolve(**PRECESSING, sampling="steps"), ell_max=3, amplitude_order=1)
    assert isinstance(h, Modes) and h.ell_m == ell_m(3) and h.data.shape == (12, len(h.t))
    assert h.inputs["ell_max"] == 3 and h.inputs["amplitude_order"] == 1.0 and h.inputs["m1_Msun"] == 30.0
    with pytest.raises(ValueError, match="mode"):
        h.mode(4, 0)
    with pytest.raises(ValueError, match=r"\('2', 2\) not in these modes"):   # the input as given, not (2, 2)
        h.mode("2", 2)
    hp, hc = h.polarizations(0.1)          # no distance anywhere: r h / M
    strain_hp, _ = h.polarizations(0.1, distance=100.0)
    np.testing.assert_allclose(strain_hp, hp * h.inputs["M_seconds"] * 299792458.0 / 3.0856775814913673e24,
                               rtol=1e-12)
    with pytest.raises(ValueError, match="frame"):
        h.in_frame("lab")


@pytest.mark.parametrize("ell, m", [(2.0, 2), (2, 1.5), (3, -0.5), ("2", 2), (None, 2), (2, True),
                                    (2, np.array([1, 2])), (4, 0), (1, 0), (3, 4)])
def test_mode_takes_integers_in_range(ell, m):
    h = modes(pnrotor.evolve(30.0, 10.0, (0, 0, 0), (0, 0, 0), 100.0, sampling="final"), ell_max=3)
    np.testing.assert_array_equal(h.mode(np.int64(3), -2), h.data[mode_index(3, -2)])
    with pytest.raises(ValueError, match="need integers 2 <= ell <= 3"):
        h.mode(ell, m)


def test_polarization_angles_are_radians_or_astropy_angles():
    u = pytest.importorskip("astropy.units")
    h = modes(pnrotor.evolve(**PRECESSING, sampling="steps"), ell_max=3)
    expected = h.polarizations(np.radians(30.0), np.radians(10.0), psi=np.radians(20.0))
    given = h.polarizations(30.0 * u.deg, 10.0 * u.deg, psi=20.0 * u.deg)
    for a, b in zip(given, expected):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15 * np.max(np.abs(b)))
    assert np.all(h.polarizations(np.float64(0.3))[0] == h.polarizations(0.3)[0])
    for name in ("inclination", "phi_ref", "psi"):
        for bad in (np.nan, np.inf, None, True, "0.3", np.array([0.1, 0.2]), 3.0 * u.s, 0.5 * u.one):
            kw = {"inclination": 0.3, name: bad}
            with pytest.raises(ValueError, match=f"{name} must be"):
                h.polarizations(**kw)


def test_modes_round_trip_through_hdf5_beside_their_run(tmp_path):
    """hdf5.write/read of Modes (kind "Modes"), alone and as a group next to the run in a batch file:
    bitwise; the complex data readable with plain h5py."""
    import h5py
    from test_hdf5 import assert_identical

    from pnrotor import hdf5
    run = pnrotor.evolve(**PRECESSING, sampling="steps")
    for distance in (None, 250.0):
        h = modes(run, ell_max=3, amplitude_order=2, distance=distance).in_frame("coprecessing")
        hdf5.write(tmp_path / "modes.h5", h, overwrite=True)
        back = hdf5.read(tmp_path / "modes.h5")
        assert isinstance(back, Modes) and back.distance_Mpc == distance and back.frame == "coprecessing"
        for name in ("t", "t_seconds", "data", "R", "Phi"):
            np.testing.assert_array_equal(getattr(back, name), getattr(h, name))
        assert back.ell_m == h.ell_m
        assert_identical(back.inputs, h.inputs, "inputs")
        with h5py.File(tmp_path / "modes.h5", "r") as f:
            np.testing.assert_array_equal(f["data"][...], h.data)
            assert f["data"].dtype == np.complex128 and f.attrs["kind"].decode() == "Modes"
    with hdf5.batch(tmp_path / "run_and_modes.h5") as runs:
        runs.add("run", run)
        runs.add("modes", modes(run, ell_max=2))
    assert sorted(hdf5.list_runs(tmp_path / "run_and_modes.h5")) == ["modes", "run"]
    np.testing.assert_array_equal(hdf5.read(tmp_path / "run_and_modes.h5", "modes").data, modes(run, ell_max=2).data)


def test_to_sxs_keeps_the_modes_and_their_sum_over_spherical_harmonics():
    """Modes.to_sxs: sxs.WaveformModes with the same h_ℓm (r h / M, t in M, from strain at a distance too);
    sxs's own Σ h_ℓm ₋₂Y_ℓm in the direction (ι, φ) is pnrotor's h₊ − i h× for (ι, φ_ref = π/2 − φ)."""
    sxs = pytest.importorskip("sxs")
    quaternionic = pytest.importorskip("quaternionic")
    run = pnrotor.evolve(30, 10, [0.6, 0.0, 0.2], [0.0, -0.4, 0.1], 20.0, sampling=1 / 4096)
    m = modes(run, ell_max=4)
    w = m.to_sxs()
    assert isinstance(w, sxs.WaveformModes) and w.spin_weight == -2 and w.ell_max == 4
    np.testing.assert_array_equal(w.t, m.t)
    for ell, mm in m.ell_m:
        np.testing.assert_array_equal(w.data[:, w.index(ell, mm)], m.mode(ell, mm))
    far = modes(run, ell_max=4, distance=250.0).to_sxs()
    np.testing.assert_allclose(far.data, w.data, rtol=1e-13, atol=0)
    for iota, phi in ((0.7, 0.4), (2.5, 5.0)):
        h = np.asarray(w.evaluate(quaternionic.array.from_spherical_coordinates(iota, phi)))
        hp, hc = m.polarizations(iota, phi_ref=np.pi / 2 - phi)
        assert np.max(np.abs(h - (hp - 1j * hc))) < 1e-14 * np.max(np.abs(hp))


def test_to_lal_is_the_interop_series():
    pytest.importorskip("lalsimulation")
    import lalsimulation as ls
    run = pnrotor.evolve(30, 10, [0.6, 0.0, 0.2], [0.0, -0.4, 0.1], 20.0, sampling=1 / 4096)
    m = modes(run, ell_max=3, distance=100.0)
    hlms = m.to_lal()
    np.testing.assert_array_equal(ls.SphHarmTimeSeriesGetMode(hlms, 3, -1).data.data, m.mode(3, -1))
