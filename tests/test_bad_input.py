"""Bad input at every public entry point: a ValueError (FileNotFoundError for a missing folder) naming
the parameter and its allowed range, raised before any integration; from the CLI a one-line error,
exit status 2 and no file written (issue 7)."""

import math
import re
import os

import numpy as np
import pytest
from ode_problems import linear

import pnrotor
import pnrotor.integrate
from pnrotor.analytic import PrecessingNutatingBinary
from pnrotor.cli import main
from pnrotor.ode import bulirsch_stoer, dop853
from pnrotor.approximants import normalize_approximant

NAN, INF = math.nan, math.inf
GOOD = dict(m1=10.0, m2=10.0, chi1=(0.0, 0.0, 0.0), chi2=(0.0, 0.0, 0.0), f_ref=20.0)

# (keyword overrides of GOOD, the parameter the message must name)
EVOLVE_CASES = [
    (dict(m1=0.0), "m1"), (dict(m2=-1.0), "m2"), (dict(m1=NAN), "m1"), (dict(m2=INF), "m2"),
    (dict(chi1=(0.0, 0.0, 1.5)), r"\|chi1\|"), (dict(chi2=(0.8, 0.8, 0.0)), r"\|chi2\|"),
    (dict(chi1=(NAN, 0.0, 0.0)), "chi1"), (dict(chi2=(0.0, INF, 0.0)), "chi2"),
    (dict(chi1=(0.1, 0.2)), "chi1"), (dict(chi2=np.zeros((2, 3))), "chi2"),
    (dict(f_ref=0.0), "f_ref"), (dict(f_ref=-5.0), "f_ref"), (dict(f_ref=NAN), "f_ref"), (dict(f_ref=INF), "f_ref"),
    (dict(f_ref=1e5), "f_ref"),  # v >= 1
    (dict(f_ref=1500.0), "f_ref"),  # v < 1 but the PN energy balance is already invalid
    (dict(f_min=NAN), "f_min"), (dict(f_min=30.0), "f_min"), (dict(f_min=-1.0), "f_min"),
    (dict(f_max=INF), "f_max"), (dict(f_max=10.0), "f_max"), (dict(f_max=0.0), "f_max"),
    (dict(f_max=1e5), "f_max"),  # v > 1 (was integrated, by T1 to v = 3.2)
    (dict(atol=0.0), "atol"), (dict(atol=-1e-12), "atol"), (dict(atol=NAN), "atol"), (dict(rtol=-1e-9), "rtol"),
    (dict(rtol=INF), "rtol"),
    (dict(ell_hat=(0.0, 0.0, 0.0)), "ell_hat"), (dict(ell_hat=(NAN, 0.0, 1.0)), "ell_hat"),
    (dict(ell_hat=np.eye(3)), "ell_hat"), (dict(n_hat=(0.0, 0.0, 0.0)), "n_hat"),
    (dict(n_hat=(1.0, 0.0)), "n_hat"), (dict(n_hat=(0.0, INF, 0.0)), "n_hat"),
    (dict(n_hat=(0.6, 0.0, 0.8)), "n_hat"),  # not orthogonal to ell_hat = ẑ
    (dict(approximant="T2"), "approximant"), (dict(approximant="EOB"), "approximant"),
    (dict(pn_order=1.25), "pn_order"), (dict(pn_order=5.0), "pn_order"), (dict(pn_order=-0.5), "pn_order"),
    (dict(pn_order=NAN), "pn_order"), (dict(spin_orbit_order=0.7), "spin_orbit_order"),
    (dict(spin_spin_order=9.0), "spin_spin_order"),
    (dict(precession="exact"), "precession"), (dict(rotor="inertial"), "rotor"),
    (dict(sampling=0.0), "sampling"), (dict(sampling=-1.0), "sampling"), (dict(sampling=NAN), "sampling"),
    (dict(sampling=("dt", INF)), "sampling"), (dict(sampling={"dt": 0.0}), "sampling"),
    (dict(sampling=("per_orbit", 0)), "sampling"), (dict(sampling=("per_orbit", -4)), "sampling"),
    (dict(sampling=("per_orbit", 2.5)), "sampling"), (dict(sampling={"per_orbit": NAN}), "sampling"),
    (dict(sampling="everything"), "sampling"), (dict(sampling=("dx", 1.0)), "sampling"),
    (dict(max_steps=0), "max_steps"),
    # issue 15: numbers at the edges, bools and NaN κ (each named, none a ZeroDivisionError or a wrong blame)
    (dict(m1=1e-300), "mass ratio"), (dict(m2=2e7), "mass ratio"), (dict(m1=True), "m1"), (dict(m2="ten"), "m2"),
    (dict(f_ref=True), "f_ref"), (dict(f_ref=1e-300), "f_ref"), (dict(f_min=1e-300), "f_min"),
    (dict(kappa1=NAN), "kappa1"), (dict(kappa2=INF), "kappa2"), (dict(kappa1=-1.0), "kappa1"),
    (dict(kappa2=True), "kappa2"), (dict(kappa1="soft"), "kappa1"), (dict(chi1=(True, 0.0, 0.0)), "chi1"),
    (dict(atol=True), "atol"), (dict(sampling=True), "sampling"),
    # options of the wrong type name themselves (a review of 2026-11-27: TypeErrors, OverflowError, "no" as True)
    (dict(atol="1e-12"), "atol"), (dict(atol=[1e-12]), "atol"), (dict(rtol=None), "rtol"),
    (dict(pn_order="abc"), "pn_order"), (dict(pn_order=True), "pn_order"), (dict(max_steps=2 ** 70), "max_steps"),
    (dict(max_steps=1e6), "max_steps"), (dict(integrate_rotor="no"), "integrate_rotor"),
    (dict(integrate_rotor=1), "integrate_rotor"), (dict(precession_phase_shift="no"), "precession_phase_shift"),
    # a review of 2026-11-27 (fifth session): integers beyond any float were OverflowErrors
    (dict(sampling=("per_orbit", 10 ** 400)), "sampling per_orbit"), (dict(sampling=("dt", 10 ** 400)), "sampling"),
    (dict(sampling=("per_orbit", 1e300)), "sampling per_orbit"), (dict(sampling=("per_orbit", 2 ** 53 + 1)), "2\\^53"),
    (dict(m1=10 ** 400), "m1"), (dict(f_ref=-10 ** 400), "f_ref"),
    (dict(chi1=(10 ** 400, 0, 0)), "chi1"), (dict(chi2=(0, 10 ** 400, 0)), "chi2"), (dict(ell_hat=(0, 0, 10 ** 400)),
                                                                                    "ell_hat"),
    (dict(n_hat=(10 ** 400, 0, 0)), "n_hat"), (dict(kappa1=10 ** 400), "kappa1"), (dict(atol=10 ** 400), "atol"),
    (dict(rtol=10 ** 400), "rtol"), (dict(pn_order=10 ** 400), "pn_order"), (dict(spin_orbit_order=10 ** 400),
                                                                              "spin_orbit_order"),
    # a review of 2026-11-28: numbers as text were taken (evolve_many refuses them)
    (dict(m1="30"), "m1"), (dict(f_ref=b"20"), "f_ref"), (dict(f_max=bytearray(b"200")), "f_max"),
    (dict(kappa1="2"), "kappa1"), (dict(pn_order="3.5"), "pn_order"), (dict(spin_spin_order=np.str_("2")),
                                                                        "spin_spin_order"),
]


@pytest.mark.parametrize("kw, name", EVOLVE_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(EVOLVE_CASES)])
def test_evolve_rejects(kw, name):
    with pytest.raises(ValueError, match=name):
        pnrotor.evolve(**{**GOOD, **kw})


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
def test_f_ref_beyond_the_end_of_the_inspiral_is_refused_where_the_events_are_positive_again(approximant):
    """The start check refuses an f_ref past the end of the inspiral (pnrotor.pn.ends.inspiral_end: the first v
    where an event fails), also beyond the band where the events are negative (the PN series turn positive again at
    higher v: a review found f_ref = 1000 Hz accepted for an aligned 30 + 10 binary whose inspiral ends at 455 Hz),
    with the same bound in the message; just below the end it runs, to that end."""
    from pnrotor.pn.initial import frequency_from_v, total_mass_seconds
    from pnrotor.pn.series import basis_values, kmax_from_orders
    from pnrotor.pn.ends import inspiral_end

    m1, m2, a1, a2 = 30.0, 10.0, 0.5, -0.3
    X1 = m1 / (m1 + m2)
    v_end = inspiral_end(X1, approximant, kmax_from_orders(3.5, 3.5, 3.0),
                         basis_values(a1, a2, a1 * a2, a1 * a1, a2 * a2))
    f_end = frequency_from_v(v_end, total_mass_seconds(m1, m2))
    kw = dict(m1=m1, m2=m2, chi1=(0.0, 0.0, a1), chi2=(0.0, 0.0, a2), approximant=approximant, sampling="final")
    run = pnrotor.evolve(**kw, f_ref=0.99 * f_end)
    assert run.v[-1] <= v_end * (1 + 1e-9)
    f_v1 = frequency_from_v(1.0, total_mass_seconds(m1, m2))
    beyond = [f for f in np.geomspace(1.01 * f_end, 3000.0, 40) if f < f_v1]
    positive_again = 0
    for f in beyond:
        with pytest.raises(ValueError, match=f"f_ref must be below {f_end:.6g} Hz"):
            pnrotor.evolve(**kw, f_ref=f)
        positive_again += "is beyond" in str(pytest.raises(ValueError, pnrotor.evolve, **kw, f_ref=f).value)
    assert positive_again > 0   # the case the review found is among them


def test_the_start_check_agrees_with_inspiral_end_and_its_bound_lies_below_f_ref(monkeypatch):
    """Aligned binaries (T1, T4, T5; χ up to ±0.99, κ 1 and 20) at v₀ from 0.1 to 0.95: evolve refuses exactly the
    f_ref at or past inspiral_end's end (none of these has a band of failing events narrower than the start check's
    grid, which can miss one: its docstring); and where the start check finds an end that inspiral_end's grid
    misses (a review found such a band, 4e-4 wide in v), the bound in the message is the start check's, below
    f_ref (it said 'below 1292.5 Hz' for f_ref = 570.7 Hz): inspiral_end made to miss here."""
    from pnrotor.pn import ends
    from pnrotor.pn.initial import frequency_from_v, total_mass_seconds
    from pnrotor.pn.series import basis_values, kmax_from_orders

    for approximant in ("T1", "T4", "T5"):
        for m1, m2, a1, a2, kappa in ((30.0, 10.0, 0.99, -0.5, 1.0), (1.4, 1.3, -0.99, 0.99, 20.0),
                                      (20.0, 20.0, 0.3, 0.2, 1.0)):
            b = basis_values(a1, a2, a1 * a2, a1 * a1, a2 * a2)
            v_end = ends.inspiral_end(m1 / (m1 + m2), approximant, kmax_from_orders(3.5, 3.5, 3.0), b, kappa,
                                      kappa)
            for v0 in np.linspace(0.1, 0.95, 18):
                f = frequency_from_v(v0, total_mass_seconds(m1, m2))
                kw = dict(chi1=(0.0, 0.0, a1), chi2=(0.0, 0.0, a2), kappa1=kappa, kappa2=kappa, sampling="final")
                if v0 < v_end:
                    pnrotor.evolve(m1, m2, f_ref=f, approximant=approximant, **kw)
                else:
                    with pytest.raises(ValueError, match="past the end"):
                        pnrotor.evolve(m1, m2, f_ref=f, approximant=approximant, **kw)
    monkeypatch.setattr(ends, "inspiral_end", lambda *args: 1.0)
    with pytest.raises(ValueError, match="it ended at a lower v") as refusal:
        pnrotor.evolve(30.0, 10.0, (0.0, 0.0, 0.5), (0.0, 0.0, -0.3), 1000.0)
    assert re.search(r"f_ref must be below 454\.6\d* Hz", str(refusal.value)), str(refusal.value)


def test_check_inputs_raises_what_evolve_raises_without_compiled_code():
    """pnrotor.pn.evolve.check_inputs (what the CLI runs before compiling) refuses every case above with evolve's
    own message, but the one whose check needs the compiled set-up (f_ref past the end of the inspiral)."""
    from pnrotor.pn.evolve import check_inputs

    for kw, _ in EVOLVE_CASES:
        with pytest.raises(ValueError) as by_evolve:
            pnrotor.evolve(**{**GOOD, **kw})
        if "past the end of the" in str(by_evolve.value):
            assert check_inputs(**{**GOOD, **kw}) is None, kw
            continue
        with pytest.raises(ValueError) as checked:
            check_inputs(**{**GOOD, **kw})
        assert str(checked.value) == str(by_evolve.value), kw
    assert check_inputs(**GOOD) is None


@pytest.mark.parametrize("sampling", [5e-324, ("per_orbit", 10 ** 13), 1 / 4096])
def test_sample_count_is_bounded_by_memory_before_allocating(sampling, monkeypatch):
    """Δt or n per orbit that would not fit: a ValueError naming sampling and the size, not a MemoryError
    or an OverflowError (the last case fits in memory unless only 1 MB is free, as pretended here)."""
    from pnrotor import processes
    if sampling == 1 / 4096:
        monkeypatch.setattr(processes, "available_memory", lambda: 2 ** 20)
    with pytest.raises(ValueError, match=r"sampling = .* would need .* samples \(.* GiB\), more than"):
        pnrotor.evolve(**GOOD, sampling=sampling)


@pytest.mark.parametrize("spins", [((0.5, 0.1, 0.3), (0.0, 0.4, -0.2)), ((0.0, 0.0, 0.3), (0.0, 0.0, -0.2))])
@pytest.mark.parametrize("sampling", [1 / 32768, ("per_orbit", 2000)])
def test_the_memory_check_counts_what_sampling_takes(spins, sampling):
    """PEAK_BYTES_PER_SAMPLE, which the memory check multiplies by the sample count, against tracemalloc's peak of
    the whole evolve call: not below its part per sample (the check would let a run run out of memory; a fixed
    1 MiB of the integration's own arrays aside), nor more than 25% above it (it would refuse runs that fit), for
    precessing and aligned runs, uniform and per orbit."""
    import tracemalloc

    from pnrotor.pn.sampling import PEAK_BYTES_PER_SAMPLE

    kw = dict(GOOD, m1=30.0, chi1=spins[0], chi2=spins[1], f_min=15.0, sampling=sampling)
    pnrotor.evolve(**kw)   # compiled, caches filled
    tracemalloc.start()
    try:
        run = pnrotor.evolve(**kw)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(run) > 10 ** 5
    bound = PEAK_BYTES_PER_SAMPLE["aligned" if spins[0][:2] == (0.0, 0.0) else "precessing"]
    assert (peak - 2 ** 20) / len(run) <= bound <= 1.25 * peak / len(run), (peak / len(run), bound)


def test_normalize_approximant_is_public():
    assert normalize_approximant("SpinTaylorT4") == normalize_approximant(" t4") == "T4"
    with pytest.raises(ValueError, match="approximant must be one of T1, T4, T5"):
        normalize_approximant("T3")


BINARY = PrecessingNutatingBinary(T=100.0)
IAV_CASES = [
    (dict(t_span=(0.0, NAN)), "t_span"), (dict(t_span=(-INF, 1.0)), "t_span"), (dict(t_span=(0.0,)), "t_span"),
    (dict(R0=np.zeros(4)), "R0"), (dict(R0=np.array([1.0, 0.0, 0.0])), "R0"),
    (dict(R0=np.array([NAN, 0.0, 0.0, 1.0])), "R0"), (dict(R0=np.ones((2, 4))), "R0"),
    (dict(formulation="euler"), "formulation"), (dict(method="RK4"), "method"),
    (dict(atol=0.0), "atol"), (dict(atol=-1.0), "atol"), (dict(atol=NAN), "atol"),
    (dict(rtol=-1e-9), "rtol"), (dict(rtol=NAN), "rtol"),
]


@pytest.mark.parametrize("kw, name", IAV_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(IAV_CASES)])
def test_integrate_angular_velocity_rejects(kw, name):
    args = {"t_span": (0.0, 10.0), "R0": np.array([1.0, 0.0, 0.0, 0.0]), **kw}
    with pytest.raises(ValueError, match=name):
        pnrotor.integrate_angular_velocity(BINARY, **args)


BINARY_CASES = [(dict(Omega_orb=NAN), "Omega_orb"), (dict(Omega_prec=INF), "Omega_prec"),
                (dict(alpha=NAN), "alpha"), (dict(alpha_dot=INF), "alpha_dot"), (dict(nu=NAN), "nu"),
                (dict(T=NAN), "T"), (dict(T=0.0), "T"), (dict(T=-1.0), "T"),
                (dict(R0=np.zeros(4)), "R0"), (dict(R0=(1.0, 0.0, 0.0)), "R0"), (dict(R0=(1.0, NAN, 0.0, 0.0)), "R0")]


@pytest.mark.parametrize("kw, name", BINARY_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(BINARY_CASES)])
def test_precessing_nutating_binary_rejects(kw, name):
    with pytest.raises(ValueError, match=name):
        PrecessingNutatingBinary(**kw)


ODE_CASES = [(dict(atol=0.0), "atol"), (dict(atol=-1e-10), "atol"), (dict(atol=NAN), "atol"),
             (dict(atol=np.ones(3) * 1e-10), "atol"), (dict(rtol=-1.0), "rtol"),
             (dict(t0=NAN), "t0"), (dict(t_end=INF), "t_end"), (dict(y0=np.array([1.0, NAN])), "y0"),
             (dict(y0=np.ones((2, 2))), "y0"), (dict(max_steps=0), "max_steps"), (dict(max_steps=-5), "max_steps")]


@pytest.mark.parametrize("solver", [dop853, bulirsch_stoer])
@pytest.mark.parametrize("kw, name", ODE_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(ODE_CASES)])
def test_ode_solvers_reject(solver, kw, name):
    args = {"t0": 0.0, "y0": np.ones(2), "t_end": 1.0, "atol": 1e-10, **kw}
    with pytest.raises(ValueError, match=name):
        solver(linear, args.pop("t0"), args.pop("y0"), args.pop("t_end"), args.pop("atol"), **args)


BASE_ARGS = ["--m1", "10", "--m2", "10", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "20"]
CLI_CASES = [  # the ones tests/test_cli_evolve.py does not already cover
    (["--m2", "inf"], "m2"), (["--f-ref", "nan"], "f_ref"), (["--f-ref", "1e5"], "f_ref"),
    (["--f-ref", "1500"], "f_ref"), (["--f-min", "inf"], "f_min"), (["--f-max", "nan"], "f_max"),
    (["--atol", "nan"], "atol"), (["--spin-orbit-order", "nan"], "spin_orbit_order"),
    (["--spin-spin-order", "0.25"], "spin_spin_order"), (["--sampling", "0"], "sampling"),
    (["--sampling", "nan"], "sampling"), (["--sampling", "per_orbit:2.5"], "sampling"),
    (["--sampling", "per_orbit:" + "9" * 401], "sampling per_orbit"), (["--sampling", "per_orbit:²"], "per_orbit:N"),
]


@pytest.mark.parametrize("extra, name", CLI_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(CLI_CASES)])
def test_cli_evolve_rejects(tmp_path, capsys, extra, name):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    code = main(["evolve", *BASE_ARGS, *extra, "-o", str(out_dir / "run.h5")])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("pnrotor evolve: error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert name in err
    assert os.listdir(out_dir) == []


VERIFY_CASES = [(["--atol", "0"], "atol"), (["--atol", "nan"], "atol"), (["--formulation", "euler"], "formulation"),
                (["--method", "RK4"], "method"), (["--t-end", "nan"], "--t-end"), (["--t-end", "0"], "--t-end"),
                (["--max-error", "-1"], "--max-error"),
                (["-o", "missing/run.h5"], "folder .*missing does not exist")]


@pytest.mark.parametrize("extra, name", VERIFY_CASES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(VERIFY_CASES)])
def test_cli_verify_rejects_before_integrating(tmp_path, capsys, monkeypatch, extra, name):
    integrate = pnrotor.integrate.integrate_angular_velocity

    def only_the_warm_up(omega, t_span, *args, **kwargs):  # verify's warm-up run spans one time unit
        assert abs(t_span[1] - t_span[0]) <= 1.0, "integrated before rejecting the input"
        return integrate(omega, t_span, *args, **kwargs)

    monkeypatch.setattr(pnrotor.integrate, "integrate_angular_velocity", only_the_warm_up)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    extra = [str(out_dir / a) if a.endswith(".h5") else a for a in extra]
    code = main(["verify", "--formulation", "vectors-damped", "-o", str(out_dir / "run.h5"), *extra])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("pnrotor verify: error: ") and err.count("\n") == 1 and re.search(name, err)
    assert os.listdir(out_dir) == []
