"""Inputs that gave silently surprising results (issue #36, items 6-10): coarse modes, angles in degrees, masked
arrays, tolerances below float64's resolution, distances out of range, frequencies an ulp apart, and the small
things a new user meets first (repr, sampling spellings, the CLI's spins).  Each test fails on the code before."""

import math
import warnings

import numpy as np
import pytest

import pnrotor
from pnrotor.cli import main
from pnrotor.waveform.modes import CoarseSamplingWarning

BINARY = (30, 10, (0.5, 0.3, 0.2), (0.0, -0.4, 0.3), 20)
BNS = (1.4, 1.3, (0.1, 0.0, 0.1), (0.0, 0.0, 0.0), 20)


def no_warning(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call()


# item 6 ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("per_orbit, coarse", [(3, True), (4, True), (5, False)])
def test_modes_and_polarizations_of_samples_too_far_apart_warn_naming_sampling(per_orbit, coarse):
    """n samples per orbit put the orbital phase 2π/n apart (Φ = 2πj/n): h22 ∝ e^{-2iΦ} has n/2 samples per cycle,
    at most two (Nyquist's limit) for n ≤ 4."""
    run = pnrotor.evolve(*BINARY, sampling=("per_orbit", per_orbit))
    if not coarse:
        no_warning(lambda: pnrotor.modes(run, ell_max=2).polarizations(0.3))
        return
    with pytest.warns(CoarseSamplingWarning, match=f"modes of a run sampled at sampling='per_orbit:{per_orbit}' are "
                                                   f"coarse: the orbital phase advances by up to {2 * math.pi / per_orbit:.3g} rad"):
        waves = pnrotor.modes(run, ell_max=2)
    with pytest.warns(CoarseSamplingWarning, match="polarizations of a run sampled at sampling="):
        waves.polarizations(0.3)


def test_the_default_steps_warn_a_uniform_grid_does_not():
    with pytest.warns(CoarseSamplingWarning, match=r"sampling='steps'.*such as sampling=1/4096"):
        pnrotor.modes(pnrotor.evolve(*BINARY), ell_max=2)
    no_warning(lambda: pnrotor.modes(pnrotor.evolve(*BINARY, sampling=1 / 4096), ell_max=2).polarizations(1.0))


def test_the_command_line_says_it_in_one_line(tmp_path, capsys):
    code = main(["evolve", "--m1", "30", "--m2", "10", "--chi1", "0.5,0.3,0.2", "--f-ref", "20", "--modes",
                 "--ell-max", "2", "-o", str(tmp_path / "run.h5")])
    err = capsys.readouterr().err
    assert code == 0
    warning, = [line for line in err.splitlines() if "warning" in line]
    assert warning.startswith("pnrotor evolve: warning: modes of a run sampled at sampling='steps' are coarse")


# item 7 ---------------------------------------------------------------------------------------------

def test_an_angle_beyond_two_pi_is_refused_as_likely_degrees():
    u = pytest.importorskip("astropy.units")
    waves = pnrotor.modes(pnrotor.evolve(*BINARY, sampling=1 / 1024), ell_max=2)
    for name, args in (("inclination", (60,)), ("phi_ref", (0.3, -7.0)), ("psi", (0.3, 0.0, None, 400.0))):
        with pytest.raises(ValueError, match=rf"^{name} = .* is outside \[-2 pi, 2 pi\]: angles are in radians "
                                             rf"\(.* degrees is .* rad; or pass an astropy angle, such as .* \* u\.deg\)"):
            waves.polarizations(*args)
    np.testing.assert_array_equal(waves.polarizations(60 * u.deg)[0], waves.polarizations(math.radians(60))[0])
    for edge in (2 * math.pi, -2 * math.pi):
        waves.polarizations(edge)
    with pytest.raises(ValueError, match="outside"):
        waves.polarizations(math.nextafter(2 * math.pi, 7))


# item 8 ---------------------------------------------------------------------------------------------

def test_evolve_many_refuses_masked_entries_and_reads_an_unmasked_masked_array():
    masked = np.ma.array([30.0, 20.0, 10.0], mask=[False, True, False])
    with pytest.raises(ValueError, match=r"^m1 has 1 masked entry \(a numpy masked array\)"):
        pnrotor.evolve_many(masked, 10, BINARY[2], BINARY[3], 20, f_end=30)
    spins = np.ma.array(np.zeros((3, 3)), mask=[[0, 0, 0], [0, 1, 1], [0, 0, 0]])
    with pytest.raises(ValueError, match=r"^chi2 has 2 masked entries"):
        pnrotor.evolve_many([30, 20, 10], 10, BINARY[2], spins, 20, f_end=30)
    with pytest.raises(ValueError, match=r"^frequencies has 1 masked entry"):
        pnrotor.evolve_many(30, 10, BINARY[2], BINARY[3], 20, frequencies=np.ma.array([25, 30], mask=[0, 1]))
    plain = pnrotor.evolve_many([30, 20], 10, BINARY[2], BINARY[3], 20, f_end=30)
    unmasked = pnrotor.evolve_many(np.ma.array([30.0, 20.0]), 10, BINARY[2], BINARY[3], 20, f_end=30)
    np.testing.assert_array_equal(unmasked.R, plain.R)


# item 9 ---------------------------------------------------------------------------------------------

def test_a_frequency_an_ulp_from_f_ref_is_too_close_not_on_the_wrong_side():
    f_max = math.nextafter(20.0, 30.0)
    with pytest.raises(ValueError, match=r"^f_max = 20.000000000000004 Hz is too close to f_ref = 20.0 Hz: both give "
                                         r"v = 0.23132884793448572 in float64"):
        pnrotor.evolve(*BINARY[:4], 20.0, f_max=f_max)
    with pytest.raises(ValueError, match=r"^f_max = 20.0 Hz must be above f_ref = 20.0 Hz"):
        pnrotor.evolve(*BINARY[:4], 20.0, f_max=20.0)
    population = pnrotor.evolve_many(30, 10, BINARY[2], BINARY[3], 20.0, frequencies=[f_max, 30.0])
    assert "is too close to f_ref" in population.message[0, 0] and population.termination[0, 1] == "f_max"


def test_one_range_of_distances_symmetric_in_the_exponent():
    """The factor a distance scales r h / M by, M c / d, may lie in [2^-511, 2^511] (its square a normal float64
    number): 5e-324 Mpc (|h| ~ 1e305) was accepted while 1e300 Mpc was refused."""
    run = pnrotor.evolve(*BINARY, sampling=1 / 1024)
    waves = pnrotor.modes(run, ell_max=2)
    mpc = 3.0856775814913673e22   # m (astropy's)
    source = run.inputs["M_seconds"] * 299792458.0   # M c in m
    for exponent, ok in ((-512, False), (-510, True), (510, True), (512, False)):
        distance = source / 2.0 ** exponent / mpc   # scale = 2^exponent
        if ok:
            strain = pnrotor.modes(run, ell_max=2, distance=distance).data
            np.testing.assert_allclose(strain, waves.data * 2.0 ** exponent, rtol=1e-14)   # nothing lost
        else:
            with pytest.raises(ValueError, match=r"^distance = .* Mpc is out of range: it scales these modes by "):
                pnrotor.modes(run, ell_max=2, distance=distance)
    for distance in (5e-324, 1e300):
        with pytest.raises(ValueError, match="out of range"):
            pnrotor.modes(run, distance=distance)
        with pytest.raises(ValueError, match="out of range"):
            waves.polarizations(0.3, distance=distance)


def test_an_atol_below_the_resolution_of_the_state_warns_naming_it():
    """The bound is the spacing of float64 numbers at the initial state's values: at the rotor's 1 for a precessing
    run in the default frame (R = 1 at f_ref), at v(f_ref) for an aligned one (state [v, Φ], Φ = 0)."""
    for args, bound in ((BINARY, np.spacing(1.0)), ((30, 10, (0, 0, 0.3), (0, 0, 0), 20), None)):
        run = pnrotor.evolve(*args)
        bound = np.spacing(run.v[0]) if bound is None else bound
        with pytest.warns(UserWarning, match=rf"^atol = {float(bound / 2)!r} is below the float64 resolution of the state: "
                                             rf"with rtol = 0.0 the tolerance must be at least {bound:.3g}"):
            pnrotor.evolve(*args, atol=bound / 2, sampling="final")
        no_warning(lambda: pnrotor.evolve(*args, atol=bound, sampling="final"))
        no_warning(lambda: pnrotor.evolve(*args, atol=bound / 2, rtol=1e-15, sampling="final"))   # rtol |y| covers it
    with pytest.warns(UserWarning, match="below the float64 resolution") as caught:
        pnrotor.evolve_many([30, 20, 25], 10, BINARY[2], BINARY[3], 20, f_end=30, atol=1e-17)
    assert len(caught) == 1


# item 10 --------------------------------------------------------------------------------------------

def test_the_repr_of_a_result_is_one_short_line():
    run = pnrotor.evolve(*BINARY, sampling=1 / 4096)
    text = repr(run)
    assert "\n" not in text and len(text) < 400 and len(run) > 9000
    assert text.startswith("Evolution(t=[0 … ") and "R=float64 (" + f"{len(run)}, 4)" in text
    assert "termination='energy_balance'" in text and "inputs={" in text
    for result in (pnrotor.modes(run, ell_max=2),
                   pnrotor.evolve_many([30, 20], 10, BINARY[2], BINARY[3], 20, frequencies=[30, 40])):
        assert "\n" not in repr(result) and len(repr(result)) < 500 and repr(result).startswith(type(result).__name__)


def test_sampling_takes_the_command_line_spellings():
    for text, value in (("1/4096", 1 / 4096), (" 0.000244 ", 0.000244), ("per_orbit:4", ("per_orbit", 4)),
                        ("PER_ORBIT:7", {"per_orbit": 7})):
        a, b = pnrotor.evolve(*BINARY, sampling=text), pnrotor.evolve(*BINARY, sampling=value)
        assert a.t.tobytes() == b.t.tobytes() and a.R.tobytes() == b.R.tobytes() and len(a) > 100
    for bad in ("fast", "1/0", [1.0], None, ("dt", 1, 2)):
        with pytest.raises(ValueError) as error:
            pnrotor.evolve(*BINARY, sampling=bad)
        for form in ("'steps'", "'final'", "a time step in seconds", "'1/4096'", "('dt', seconds)",
                     "{'dt': seconds}", "('per_orbit', n)", "{'per_orbit': n}", "'per_orbit:n'"):
            assert form in str(error.value), (bad, form)


def test_the_command_line_spins_default_to_zero(tmp_path, capsys):
    code = main(["evolve", "--m1", "30", "--m2", "10", "--f-ref", "20", "-o", str(tmp_path / "run.h5")])
    assert code == 0, capsys.readouterr().err
    run, expected = pnrotor.hdf5.read(tmp_path / "run.h5"), pnrotor.evolve(30, 10, (0, 0, 0), (0, 0, 0), 20)
    assert run.inputs["spin_content"] == "nonspinning" and run.v.tobytes() == expected.v.tobytes()
    assert main(["evolve", "--m2", "10", "--f-ref", "20"]) == 2
    assert capsys.readouterr().err.strip() == "pnrotor evolve: error: missing --m1 (or give --batch FILE)"
