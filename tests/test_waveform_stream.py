"""pnrotor.waveform.stream: a run's history, modes and polarizations computed block by block from the dense output
equal the Evolution → modes → polarizations route (history and modes bitwise, polarizations to 1e-13 of max|h|) on
BBH, NSBH and BNS binaries; the one-call pnrotor.polarizations and pnrotor.modes; the line-of-sight identity the
polarizations use; memory refusals that name the streaming write; streamed HDF5 files; the CLI's --polarizations."""

import dataclasses
import os

import h5py
import numpy as np
import pytest

import pnrotor
from pnrotor import hdf5, threads
from pnrotor.waveform import stream as S
from pnrotor.waveform.layout import ell_m
from pnrotor.waveform.polarizations import swsh
from pnrotor.waveform.wigner import wigner_D

DT = 1.0 / 4096
CASES = {   # (m1, m2, χ₁, χ₂, f_ref, options): a precessing BBH, NSBH (both halves) and BNS (both halves, to f_max)
    "BBH": (30.0, 10.0, (0.5, 0.3, 0.2), (0.0, -0.4, 0.3), 25.0, {}),
    "NSBH": (10.0, 1.4, (0.6, 0.1, 0.3), (0.02, 0.0, 0.01), 60.0, dict(f_min=55.0)),
    "BNS": (1.4, 1.3, (0.03, 0.02, 0.03), (0.0, -0.04, 0.01), 150.0, dict(f_min=140.0, f_max=400.0)),
    "aligned, tilted frame": (10.0, 8.0, (0.0, 0.18, 0.24), (0.0, 0.12, 0.16), 40.0,
                              dict(ell_hat=(0.0, 0.6, 0.8), n_hat=(1.0, 0.0, 0.0))),
    "nonspinning": (10.0, 5.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 60.0, dict(f_min=55.0)),
}
ARRAYS = ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat")


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    m1, m2, chi1, chi2, f_ref, options = CASES[request.param]
    binary = (m1, m2, chi1, chi2, f_ref)
    return binary, options, pnrotor.evolve(*binary, sampling=DT, **options), pnrotor.stream(*binary, delta_t=DT,
                                                                                           **options)


def test_history_and_modes_are_the_evolutions_bitwise(case):
    """The streamed history is evolve's with sampling=Δt and the streamed modes modes(evolve(…))'s, bitwise (the same
    kernels on the same samples in the same blocks), at ℓ ≤ 8 3.5PN in strain, ℓ ≤ 4 1.5PN in r h / M and ℓ = 2
    Newtonian (no spin term: the precessing runs' spins are then not interpolated)."""
    binary, options, run, stream = case
    assert len(stream) == len(run) > 2 * 1024   # several blocks and two parts on the threads
    evolution = stream.evolution().compute()
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(evolution, name), getattr(run, name), err_msg=name)
    assert evolution.termination == run.termination and evolution.inputs == run.inputs
    for args in ((8, 3.5, 100.0), (4, 1.5, None), (2, 0, 100.0)):
        h, expected = stream.modes(*args).compute(), pnrotor.modes(run, *args)
        for name in ("t", "t_seconds", "data", "R", "Phi"):
            np.testing.assert_array_equal(getattr(h, name), getattr(expected, name), err_msg=name)
        assert h.inputs == expected.inputs and h.distance_Mpc == expected.distance_Mpc


def test_polarizations_are_the_modes_sum_to_rounding(case):
    """pnrotor.polarizations (the modes m = 2 in the frame of the line of sight) against the inertial modes' sum
    Modes.polarizations: within 1e-13 of max|h| (measured ~2e-15) for every case, ℓ ≤ 8, ℓ ≤ 4 and ℓ = 2
    Newtonian; t is evolve's t_seconds."""
    binary, options, run, stream = case
    for ell_max, order, inclination, phi_ref in ((8, 3.5, 0.7, 0.3), (4, 1.5, 2.9, -1.2), (2, 0, 1.1, 0.4)):
        t, hp, hc = pnrotor.polarizations(*binary, inclination=inclination, distance=100.0, delta_t=DT,
                                          phi_ref=phi_ref, ell_max=ell_max, amplitude_order=order, **options)
        ep, ec = pnrotor.modes(run, ell_max, order, 100.0).polarizations(inclination, phi_ref)
        np.testing.assert_array_equal(t, run.t_seconds)
        assert all(x.dtype == np.float64 and x.shape == (len(run),) for x in (t, hp, hc))
        scale = max(np.abs(ep).max(), np.abs(ec).max())
        assert np.abs(hp - ep).max() <= 1e-13 * scale and np.abs(hc - ec).max() <= 1e-13 * scale


def test_modes_of_a_binary_are_the_streams():
    """pnrotor.modes with a binary's parameters: modes(evolve(…)) bitwise; with an Evolution as before; anything else
    a TypeError saying what it takes."""
    m1, m2, chi1, chi2, f_ref, options = CASES["BNS"]
    h = pnrotor.modes(m1, m2, chi1, chi2, f_ref, delta_t=DT, ell_max=3, amplitude_order=1, **options)
    run = pnrotor.evolve(m1, m2, chi1, chi2, f_ref, sampling=DT, **options)
    np.testing.assert_array_equal(h.data, pnrotor.modes(run, 3, 1).data)
    with pytest.raises(TypeError, match="modes\\(\\) takes an Evolution .* or a binary's m1, m2"):
        pnrotor.modes("run.h5")


def test_tides_and_memory_stream_as_the_evolutions():
    """A tidal BNS, precessing, with the memory: the streamed modes are modes(evolve(…), memory=True)'s bitwise, with
    the run's tidal amplitude terms, and the one-call polarizations their sum to 1e-13 of max|h|; the tidal and memory
    terms are really there (the modes differ from those without by more than rounding)."""
    binary, options = (1.4, 1.3, (0.3, 0.1, 0.1), (0.0, 0.0, 0.0), 150.0), dict(f_min=140.0, lambda1=400.0,
                                                                                 lambda2=600.0)
    run = pnrotor.evolve(*binary, sampling=DT, **options)
    expected = pnrotor.modes(run, distance=100.0, memory=True)
    h = pnrotor.modes(*binary, delta_t=DT, distance=100.0, memory=True, **options)
    np.testing.assert_array_equal(h.data, expected.data)
    assert h.inputs == expected.inputs and h.inputs["memory"] and h.inputs["tidal_amplitude_order"] == 6.0
    plain = pnrotor.modes(run, distance=100.0, tidal_order=0)
    assert np.max(np.abs(expected.data - plain.data)) > 1e-6 * np.max(np.abs(plain.data))
    t, hp, hc = pnrotor.polarizations(*binary, inclination=0.7, distance=100.0, delta_t=DT, memory=True, **options)
    php, phc = expected.polarizations(0.7)
    peak = np.max(np.abs(php))
    assert np.max(np.abs(hp - php)) < 1e-13 * peak and np.max(np.abs(hc - phc)) < 1e-13 * peak


def test_thread_count_does_not_change_the_numbers(monkeypatch):
    """Polarizations and modes on one thread and in parts on three: bitwise the same (each sample by the same
    code)."""
    m1, m2, chi1, chi2, f_ref, options = CASES["NSBH"]
    stream = pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=DT, **options)
    wave = (stream.polarizations(inclination=0.4, distance=50.0), stream.modes(5, 2.5))
    handed = []
    run = threads.run
    monkeypatch.setattr(threads, "run", lambda kernel, ranges: (handed.append(len(ranges)), run(kernel, ranges)))
    monkeypatch.setattr(threads, "thread_count", lambda: 3)
    monkeypatch.setattr(threads, "PART_SECONDS", 0.0)   # parts of any length
    many = [w.compute() for w in wave]
    assert handed == [3, 3]
    monkeypatch.setattr(threads, "thread_count", lambda: 1)
    one = [w.compute() for w in wave]
    assert handed[2:] == [1, 1]
    np.testing.assert_array_equal(one[0].h_plus, many[0].h_plus)
    np.testing.assert_array_equal(one[0].h_cross, many[0].h_cross)
    np.testing.assert_array_equal(one[1].data, many[1].data)


@pytest.mark.parametrize("inclination, phi", [(0.7, 1.2), (2.3, -0.4), (0.0, 0.3), (np.pi, 2.0), (1e-9, 5.0)])
def test_harmonics_seen_from_their_pole_have_only_m_2(inclination, phi):
    """Σ_m ₋₂Y_ℓm(ι, φ) 𝔇^ℓ_{m m'}(R_n) = √((2ℓ+1)/4π) δ_{m'2} for the rotor R_n of _line_of_sight, every ℓ ≤ 8:
    from swsh (Goldberg's sum) and wigner_D (Wigner's), to 4e-15 (a few roundings of terms up to ~1)."""
    Rn, weights = S._line_of_sight(inclination, phi, 8)
    Y = np.array([complex(swsh(-2, ell, m, inclination, phi)) for ell, m in ell_m(8)])
    row = Y @ wigner_D(Rn, 8)
    expected = np.array([weights[ell] * (m == 2) for ell, m in ell_m(8)])
    np.testing.assert_allclose(row, expected, rtol=0, atol=4e-15)


def test_blocks_are_the_samples_of_the_whole():
    """block(lo, hi) of each kind: the samples lo … hi−1 of compute(), bitwise (blocks from multiples of 256 as the
    HDF5 writer takes them; the history from any sample); a range outside the run is a ValueError."""
    m1, m2, chi1, chi2, f_ref, options = CASES["NSBH"]
    stream = pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=DT, **options)
    n = len(stream)
    for streamed, name, starts in ((stream.evolution(), "R", range(0, n, 1000)),
                                   (stream.modes(4, 1.5), "data", range(0, n, 1536)),
                                   (stream.polarizations(inclination=1.0, distance=10.0), "h_plus", range(0, n, 2560))):
        whole = getattr(streamed.compute(), name)
        pieces = [getattr(streamed.block(lo, min(n, lo + starts.step)), name) for lo in starts]
        np.testing.assert_array_equal(np.concatenate(pieces, axis=whole.ndim - 1 if name == "data" else 0), whole)
        for lo, hi in ((0, 0), (-1, 5), (0, n + 1), (0.0, 5)):
            with pytest.raises(ValueError, match="block needs integers 0 <= lo < hi"):
                streamed.block(lo, hi)


def test_results_too_large_for_memory_name_the_streaming_write(monkeypatch):
    """compute() of each kind, evolve with that sampling and modes() of that run, when they would not fit (as
    pretended here): a ValueError with the size that names pnrotor.stream and hdf5.write, before allocating."""
    from pnrotor import processes
    m1, m2, chi1, chi2, f_ref, options = CASES["BBH"]
    stream = pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=DT)
    run = pnrotor.evolve(m1, m2, chi1, chi2, f_ref, sampling=DT)
    n = len(stream)
    sizes = {"Evolution": 136 * n, "Modes": (16 * 77 + 56) * n, "Polarizations": 24 * n}
    for streamed in (stream.evolution(), stream.modes(), stream.polarizations(inclination=0.0, distance=1.0)):
        monkeypatch.setattr(processes, "available_memory", lambda: sizes[streamed.kind])
        with pytest.raises(ValueError, match=f"{streamed.kind}: {n} samples would need .* GiB, more than .*; choose "
                                             f".* or write them to a file block by block: pnrotor.hdf5.write\\(path, "
                                             f"pnrotor.stream\\("):
            streamed.compute()
        monkeypatch.setattr(processes, "available_memory", lambda: sizes[streamed.kind] + 1)
        assert len(getattr(streamed.compute(), "t_seconds")) == n
    monkeypatch.setattr(processes, "available_memory", lambda: 1 << 10)
    with pytest.raises(ValueError, match="sampling = .* or write the history to a file block by block: .*"
                                         "pnrotor.stream\\(.*\\).evolution\\(\\)"):
        pnrotor.evolve(m1, m2, chi1, chi2, f_ref, sampling=DT)
    with pytest.raises(ValueError, match="modes\\(\\): 77 modes .* pnrotor.stream\\(.*\\).modes\\(...\\)"):
        pnrotor.modes(run)


@pytest.mark.parametrize("call, error, message", [
    (lambda b: pnrotor.polarizations(*b, inclination=0.1, distance=1.0, delta_t=-1.0), ValueError,
     "delta_t must be a finite positive time in seconds"),
    (lambda b: pnrotor.polarizations(*b, inclination="x", distance=1.0, delta_t=DT), ValueError,
     "inclination must be a finite angle in radians"),
    (lambda b: pnrotor.polarizations(*b, inclination=0.1, distance=0.0, delta_t=DT), ValueError,
     "distance must be a finite positive"),
    (lambda b: pnrotor.polarizations(*b, inclination=0.1, distance=1.0, delta_t=DT, ell_max=9), ValueError,
     "ell_max must be an integer from 2 to 8"),
    (lambda b: pnrotor.polarizations(*b, inclination=0.1, distance=1.0, delta_t=DT, sampling="steps"), TypeError,
     "unexpected keyword argument 'sampling'"),
    (lambda b: pnrotor.polarizations(*b, inclination=0.1, distance=1.0, delta_t=DT, atoll=1e-9), TypeError,
     "unexpected keyword argument 'atoll'"),
    (lambda b: pnrotor.polarizations(*b, distance=1.0, delta_t=DT), TypeError, "inclination"),
    (lambda b: pnrotor.stream(*b, delta_t=DT).polarizations(inclination=0.1, distance=None), ValueError,
     "distance is required"),
    (lambda b: pnrotor.modes(*b, delta_t=DT, amplitude_order=4.5), ValueError, "amplitude_order must be one of"),
])
def test_bad_arguments_name_themselves(call, error, message):
    with pytest.raises(error, match=message):
        call((30.0, 10.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 100.0))


@pytest.fixture
def small_blocks(monkeypatch):
    """Streamed writes in blocks of 1,024 samples (a few blocks for the cases here), each block's size recorded."""
    monkeypatch.setattr(hdf5, "_STREAM_SAMPLES", 1024)
    sizes = []
    block = S.Streamed.block

    def recorded(self, lo, hi):
        sizes.append(hi - lo)
        return block(self, lo, hi)

    monkeypatch.setattr(S.Streamed, "block", recorded)
    return sizes


@pytest.mark.parametrize("storage", [dict(), dict(checksum=False), dict(compression="lzf")])
def test_streamed_files_are_the_computed_results(tmp_path, small_blocks, storage):
    """hdf5.write of each streamed kind, and Batch.add: the file reads back as compute() (bitwise), written a block
    at a time (no block larger than the writer's), chunked along the time axis (a mode's samples in chunks of their
    own) or contiguous without checksum and compression."""
    m1, m2, chi1, chi2, f_ref, options = CASES["BNS"]
    stream = pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=DT, **options)
    kinds = {"run": stream.evolution(), "modes": stream.modes(3, 1.0, 40.0),
             "pol": stream.polarizations(inclination=0.5, distance=40.0, ell_max=3)}
    with hdf5.batch(tmp_path / "b.h5", **storage) as batch:
        for name, streamed in kinds.items():
            hdf5.write(tmp_path / f"{name}.h5", streamed, **storage)
            batch.add(name, streamed)
    assert small_blocks and max(small_blocks) == 1024 and sum(small_blocks) == 6 * len(stream)
    for name, streamed in kinds.items():
        expected = streamed.compute()
        for got in (hdf5.read(tmp_path / f"{name}.h5"), hdf5.read(tmp_path / "b.h5", name)):
            assert type(got) is type(expected)
            for field in dataclasses.fields(expected):
                a, b = getattr(got, field.name), getattr(expected, field.name)
                if isinstance(b, np.ndarray):
                    np.testing.assert_array_equal(a, b)
                elif field.name != "stats":
                    assert a == b or (a != a and b != b), field.name
    with h5py.File(tmp_path / "modes.h5") as f:
        chunks = {name: f[name].chunks for name in ("data", "R", "t")}
    n = min(len(stream), 1024)   # 2^k steps of at most 1 MiB, 2^16 (modes), 2^15 (R), 2^17 (t), and at most a block
    assert chunks == ({"data": None, "R": None, "t": None} if storage == dict(checksum=False) else
                      {"data": (1, n), "R": (n, 4), "t": (n,)})


def test_a_bad_block_leaves_no_file(tmp_path, small_blocks, monkeypatch):
    """A non-finite value in a later block: the ValueError of a run's check, naming the samples, and neither the file
    nor a temporary one."""
    stream = pnrotor.stream(*CASES["BNS"][:5], delta_t=DT, **CASES["BNS"][5])
    streamed = stream.polarizations(inclination=0.5, distance=40.0, ell_max=2)
    block = S.Streamed.block

    def spoiled(self, lo, hi):
        result = block(self, lo, hi)
        if lo >= 2048:
            result.h_plus[3] = np.nan
        return result

    monkeypatch.setattr(S.Streamed, "block", spoiled)
    with pytest.raises(ValueError, match="cannot write this Polarizations: dataset 'h_plus' has 1 non-finite value "
                                         ".* \\(of samples 2048 ... 3071\\)"):
        hdf5.write(tmp_path / "p.h5", streamed)
    assert os.listdir(tmp_path) == []


def test_cli_writes_polarizations_beside_the_run_and_modes(tmp_path, capsys, monkeypatch):
    """pnrotor evolve --sampling 1/4096 --modes --polarizations: groups run, modes and polarizations, each what the
    library computes (the run evolve's, bitwise); --polarizations needs a time step, an inclination and a distance,
    and applies to one run; --inclination applies to --polarizations."""
    from pnrotor.cli import main
    monkeypatch.chdir(tmp_path)
    m1, m2, chi1, chi2, f_ref, options = CASES["BNS"]
    binary = ["--m1", "1.4", "--m2", "1.3", "--chi1", "0.03,0.02,0.03", "--chi2", "0,-0.04,0.01", "--f-ref", "150",
              "--f-min", "140", "--f-max", "400"]
    code = main(["evolve", *binary, "--sampling", "1/4096", "--modes", "--ell-max", "3", "--polarizations",
                 "--inclination", "0.6", "--phi-ref", "0.2", "--distance", "40", "-o", "w.h5"])
    out = capsys.readouterr().out
    assert code == 0 and "groups         run, modes, polarizations" in out and "polarizations  h+, hx at inclination 0.6" in out
    stream = pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=DT, **options)
    run = pnrotor.evolve(m1, m2, chi1, chi2, f_ref, sampling=DT, **options)
    stored = hdf5.read("w.h5", "run")
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(stored, name), getattr(run, name))
    np.testing.assert_array_equal(hdf5.read("w.h5", "modes").data, pnrotor.modes(run, 3, 3.5, 40.0).data)
    p = hdf5.read("w.h5", "polarizations")
    expected = stream.polarizations(inclination=0.6, phi_ref=0.2, distance=40.0, ell_max=3).compute()
    np.testing.assert_array_equal(p.h_plus, expected.h_plus)
    assert (p.inclination, p.phi_ref, p.distance_Mpc) == (0.6, 0.2, 40.0)
    assert main(["inspect", "w.h5", "--group", "polarizations"]) == 0
    assert "h+, hx at inclination 0.6 rad, phi_ref 0.2 rad, strain at 40 Mpc" in capsys.readouterr().out
    for extra, message in ((["--polarizations", "--inclination", "1", "--distance", "1"], "needs a time step"),
                           (["--sampling", "1/4096", "--polarizations", "--distance", "1"], "needs --inclination"),
                           (["--sampling", "1/4096", "--inclination", "1"], "--inclination applies to --polarizations"),
                           (["--sampling", "1/4096", "--polarizations", "--inclination", "nan", "--distance", "1"],
                            "--inclination must be a finite angle")):
        assert main(["evolve", *binary, *extra, "-o", "x.h5"]) == 2
        assert message in capsys.readouterr().err and not os.path.exists("x.h5")
    assert main(["evolve", "--batch", "b.csv", "--polarizations"]) == 2
    assert "--polarizations applies to one run, not to --batch" in capsys.readouterr().err
