"""pnrotor.threads: the parts of a split call, running them, and the modes kernel computed in parts."""

import multiprocessing
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from helpers import default_signals
from hypothesis import strategies as st

from pnrotor import threads
from pnrotor.waveform import amplitudes, wigner


@settings(max_examples=300, deadline=None)
@given(n=st.integers(0, 100_000), min_part=st.integers(1, 5_000), align=st.sampled_from([1, 7, 256]),
       count=st.integers(1, 8))
def test_parts_cover_the_range_in_order(n, min_part, align, count):
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(threads, "thread_count", lambda: count)
        ranges = threads.parts(n, min_part, align)
    assert ranges[0][0] == 0 and ranges[-1][1] == n
    assert all(a[1] == b[0] for a, b in zip(ranges, ranges[1:]))
    assert 1 <= len(ranges) <= count
    if len(ranges) > 1:
        assert all(hi - lo >= max(align, min_part - align) for lo, hi in ranges)
        assert all(lo % align == 0 for lo, _ in ranges)
    else:
        assert n < 2 * max(min_part, align) or count == 1


@pytest.mark.parametrize("seconds_per_sample, parts", [(1e-9, 1), (1e-7, 1), (1.5e-7, 2), (2e-6, 3)])
def test_run_timed_hands_out_only_parts_of_a_millisecond(monkeypatch, seconds_per_sample, parts):
    """A kernel of 20,000 samples costing (on a clock the kernel advances) 1 ns, 0.1, 0.15 and 2 µs each: after the
    timed first samples, here, the other 17,952 stay here at 1 ns and at 0.1 µs (two parts would have 0.9 ms each),
    go in two parts at 0.15 µs (three would have 0.9 ms) and in three at 2 µs; the calls cover the range in order,
    in blocks."""
    clock = [0.0]
    calls = []

    def kernel(lo, hi):
        calls.append((lo, hi, threading.get_ident()))
        clock[0] += (hi - lo) * seconds_per_sample

    monkeypatch.setattr(threads.time, "perf_counter", lambda: clock[0])
    monkeypatch.setattr(threads, "thread_count", lambda: 3)
    threads.run_timed(kernel, 20_000, 256)
    ranges = sorted((lo, hi) for lo, hi, _ in calls)
    assert calls[0][:2] == (0, threads.TIMED_SAMPLES) and calls[0][2] == threading.get_ident()
    assert len(calls) == 1 + parts and ranges[0][0] == 0 and ranges[-1][1] == 20_000
    assert all(a[1] == b[0] and b[0] % 256 == 0 for a, b in zip(ranges, ranges[1:]))
    assert all((hi - lo) * seconds_per_sample >= threads.PART_SECONDS for lo, hi in ranges[1:]) or parts == 1


def test_an_error_here_waits_for_the_running_parts_and_drops_the_others():
    done, started = [], []
    running = threading.Event()

    def kernel(lo, hi):
        if lo == 0:
            running.wait(5)   # a worker is computing a part
            raise ValueError("first part")
        started.append(lo)
        running.set()
        time.sleep(0.2)
        done.append(lo)

    with pytest.raises(ValueError, match="first part"):
        threads.run(kernel, [(0, 1), (1, 2), (2, 3)])
    at_return = sorted(done)
    time.sleep(0.5)
    assert started and sorted(started) == at_return == sorted(done)   # what started had ended; nothing ran after
    assert threads._busy == 0


def test_run_raises_a_workers_error():
    seen = []

    def kernel(lo, hi):
        if lo:
            raise RuntimeError(f"part {lo}")
        seen.append(threading.current_thread() is threading.main_thread())

    with pytest.raises(RuntimeError, match="part 5"):
        threads.run(kernel, [(0, 5), (5, 9)])
    assert seen == [True]   # the first part on the calling thread


def _precessing_samples(n):
    rng = np.random.default_rng(7)
    v = np.linspace(0.2, 0.4, n)
    chi1, chi2 = 0.5 * rng.normal(size=(n, 3)), 0.4 * rng.normal(size=(n, 3))
    R = rng.normal(size=(n, 4))
    return v, chi1, chi2, R


@pytest.mark.parametrize("frame", ["rotors", "z", "coorbital"])
@pytest.mark.parametrize("n", [700, 5_001])
def test_modes_in_parts_bitwise_equal_one_part(monkeypatch, frame, n):
    v, chi1, chi2, R = _precessing_samples(n)
    if frame == "z":
        chi1 = chi2 = None
        R[:, 1:3] = 0.0

    def modes(count):
        monkeypatch.setattr(threads, "thread_count", lambda: count)
        return amplitudes.modes_in_frame(v, chi1, chi2, 30.0, 10.0, 5, 7, R=R, frame=frame)

    monkeypatch.setattr(wigner, "MIN_PART", 1)
    one, three = modes(1), modes(3)
    assert threads.parts(n, 1, 256) != [(0, n)]    # really in parts
    assert np.array_equal(one, three) and np.all(np.isfinite(one))


@pytest.mark.parametrize("n", [700, 5_001])
def test_rotate_modes_in_parts_bitwise_equal_one_part(monkeypatch, n):
    rng = np.random.default_rng(3)
    H = rng.normal(size=(wigner.n_modes(6), n)) + 1j * rng.normal(size=(wigner.n_modes(6), n))
    R = rng.normal(size=(n, 4))
    monkeypatch.setattr(wigner, "MIN_PART", 1)
    monkeypatch.setattr(threads, "thread_count", lambda: 1)
    one = wigner.rotate_modes(H, R, 6)
    monkeypatch.setattr(threads, "thread_count", lambda: 3)
    assert np.array_equal(one, wigner.rotate_modes(H, R, 6))
    # and the rotation itself: h = D(R) H per sample, D from wigner_D (one kernel call per sample's columns)
    D = wigner.wigner_D(R[:5], 6)
    assert np.allclose(one[:, :5], np.einsum("sjk,ks->js", D, H[:, :5]), rtol=0, atol=1e-13)


def _child_modes(queue):
    v, chi1, chi2, R = _precessing_samples(5_000)
    queue.put(amplitudes.modes_in_frame(v, chi1, chi2, 30.0, 10.0, 4, 3, R=R, frame="rotors")[3, -1])


def test_a_forked_child_splits_with_its_own_pool(monkeypatch):
    monkeypatch.setattr(threads, "thread_count", lambda: 2)
    v, chi1, chi2, R = _precessing_samples(5_000)
    expected = amplitudes.modes_in_frame(v, chi1, chi2, 30.0, 10.0, 4, 3, R=R, frame="rotors")[3, -1]  # pool made
    queue = multiprocessing.get_context("fork").Queue()
    child = multiprocessing.get_context("fork").Process(target=_child_modes, args=(queue,))
    child.start()
    child.join(60)
    hung = child.is_alive()
    child.kill()
    assert not hung, "the forked child hung (the parent's pool threads do not exist in it)"
    assert queue.get(timeout=5) == expected


def test_limit_caps_the_threads_and_checks_its_argument():
    before = threads.thread_count()
    try:
        threads.limit(1)
        assert threads.thread_count() == 1 and threads.parts(10**6, 1) == [(0, 10**6)]
        threads.limit(10**6)
        assert threads.thread_count() == before
    finally:
        threads.limit(None)
    assert threads.thread_count() == before
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="count must be None or an integer >= 1"):
            threads.limit(bad)


def test_limited_caps_this_thread_only_inside_its_block():
    before = threads.thread_count()
    seen = {}
    with threads.limited(1):
        seen["here"] = threads.thread_count()
        other = threading.Thread(target=lambda: seen.setdefault("other", threads.thread_count()))
        other.start()
        other.join()
        assert threads.parts(10**6, 1) == [(0, 10**6)]
    assert seen == {"here": 1, "other": before} and threads.thread_count() == before
    with pytest.raises(ValueError, match="count must be None or an integer >= 1"):
        with threads.limited(0):
            pass
    assert threads.thread_count() == before


def test_dask_tasks_take_one_thread_each_and_leave_the_process_alone(monkeypatch):
    """A batch's Dask tasks (an in-process cluster: the tasks run in this process, on the worker's threads) compute
    on one thread each; this process's own calls keep theirs."""
    distributed = pytest.importorskip("distributed")
    from pnrotor.batch import backends

    monkeypatch.setattr(backends, "attempt_chunk", lambda chunk: [(index, True, threads.thread_count())
                                                                  for index, _ in chunk])
    before = threads.thread_count()
    with distributed.LocalCluster(n_workers=1, processes=False, threads_per_worker=2,
                                  dashboard_address=None) as cluster:
        results = list(backends._dask_results(distributed.Client(cluster, set_as_default=False), [(0, {}), (1, {})]))
    assert sorted(results) == [(0, True, 1), (1, True, 1)]
    assert threads.thread_count() == before


def test_batch_workers_take_one_thread_each():
    from concurrent.futures import ProcessPoolExecutor

    from pnrotor.batch.backends import _preload

    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("forkserver"), initializer=_preload) as pool:
        assert pool.submit(threads.thread_count).result(timeout=120) == 1


def test_a_ctrl_c_while_waiting_is_raised_after_every_part(default_sigint):
    done = []
    claimed, sent = threading.Event(), threading.Event()

    def interrupt():
        os.kill(os.getpid(), signal.SIGINT)
        sent.set()

    def kernel(lo, hi):
        if lo:   # a worker's part: the Ctrl-C comes while it runs and the caller waits for it
            claimed.set()
            assert sent.wait(10)
            time.sleep(0.1)
            done.append(lo)
        else:
            assert claimed.wait(10)
            threading.Timer(0.05, interrupt).start()

    with pytest.raises(KeyboardInterrupt):
        threads.run(kernel, [(0, 1), (1, 2)])
    assert done == [1]


def test_workers_are_reused_across_part_counts(monkeypatch):
    monkeypatch.setattr(threads, "thread_count", lambda: 4)
    assert threads.stop_idle_workers()
    for n in (2, 3, 4, 3, 2, 4):
        threads.run(lambda lo, hi: None, threads.parts(n, 1))
    assert len(threads._workers) <= 3 and threads._busy == 0


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork is the start method on Linux only")
def test_batches_stop_idle_workers_and_fork(monkeypatch):
    from pnrotor.batch.backends import start_method

    monkeypatch.setattr(threads, "thread_count", lambda: 2)
    threads.run(lambda lo, hi: None, threads.parts(2, 1))
    assert any(t.name.startswith("pnrotor-") for t in threading.enumerate())
    others = [t for t in threading.enumerate() if t is not threading.current_thread()
              and not t.name.startswith("pnrotor-")]
    assert start_method() == ("forkserver" if others else "fork")
    assert not any(t.name.startswith("pnrotor-") for t in threading.enumerate())
    threads.run(lambda lo, hi: None, threads.parts(2, 1))   # and they start again
    assert threads._workers and threads._busy == 0


def test_concurrent_and_nested_calls_do_not_wait_for_a_free_worker(monkeypatch):
    monkeypatch.setattr(threads, "thread_count", lambda: 2)
    assert threads.stop_idle_workers()   # from none: each call starts only the workers it lacks
    seen = []

    def slow(lo, hi):
        time.sleep(0.5)
        seen.append(lo)

    callers = [threading.Thread(target=threads.run, args=(slow, [(0, 1), (1, 2)])) for _ in range(4)]
    t0 = time.perf_counter()
    for c in callers:
        c.start()
    for c in callers:
        c.join()
    assert len(seen) == 8 and time.perf_counter() - t0 < 1.5   # with one worker for four callers: 2 s

    def outer(lo, hi):   # a split call from inside a part (a worker's or the caller's)
        threads.run(lambda a, b: seen.append((a, b)), [(0, 1), (1, 2)])

    done = threading.Thread(target=threads.run, args=(outer, [(0, 1), (1, 2)]), daemon=True)
    done.start()
    done.join(10)
    assert not done.is_alive()


def test_a_workers_error_leaves_no_reference_cycle_holding_the_arrays(monkeypatch):
    import gc
    import weakref

    class Big:
        pass

    def call():
        big = Big()

        def kernel(lo, hi):
            if lo:
                raise ValueError(str(type(big)))

        with pytest.raises(ValueError):
            threads.run(kernel, [(0, 1), (1, 2)])
        return weakref.ref(big)

    gc.disable()
    try:
        assert call()() is None
    finally:
        gc.enable()


def test_a_split_call_during_finalization_runs_here():
    code = textwrap.dedent("""
        import sys
        from pnrotor import threads
        threads.run(lambda lo, hi: None, [(0, 1), (1, 2)])   # a worker exists

        class Late:
            def __del__(self):
                out = []
                threads.run(lambda lo, hi: out.append((lo, hi)), [(0, 1), (1, 2)])
                print("finalizing", sys.is_finalizing(), out, flush=True)

        keep = Late()
        keep.self = keep   # a cycle: collected at finalization
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "[(0, 2)]" in done.stdout or "[(0, 1), (1, 2)]" in done.stdout, done.stdout


@pytest.mark.parametrize("where", ["atexit", "thread"])
def test_split_calls_work_at_interpreter_shutdown(where):
    """Modes of 5,000 samples from an atexit handler or a thread still running when the main thread ends (a
    concurrent.futures pool refuses work then)."""
    code = textwrap.dedent(f"""
        import atexit, threading
        import numpy as np
        from pnrotor.waveform import amplitudes

        def modes():
            v = np.linspace(0.2, 0.4, 5000)
            h = amplitudes.modes_in_frame(v, None, None, 30.0, 10.0, 4, 3)
            print("ok", h.shape, np.isfinite(h).all(), flush=True)

        if "{where}" == "atexit":
            atexit.register(modes)
        else:
            threading.Thread(target=lambda: (threading.main_thread().join(), modes())).start()
    """)
    env = dict(os.environ, NUMBA_NUM_THREADS="2")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    assert "ok (21, 5000) True" in done.stdout


def test_ctrl_c_at_any_moment_leaves_no_part_running_and_the_counts_right():
    """Real SIGINTs at random moments around 400 three-part calls (a review's stress test): after each call no part
    writes any more, the count of parts out comes back to 0, nothing hangs."""
    code = textwrap.dedent("""
        import os, random, signal, time
        from pnrotor import threads
        signal.signal(signal.SIGALRM, lambda signum, frame: os.kill(os.getpid(), signal.SIGINT))
        random.seed(1)
        late = interrupted = 0
        for i in range(400):
            finished = []
            def kernel(lo, hi):
                if lo:
                    x = 0
                    for _ in range(300):
                        x += 1
                    finished.append(lo)
            try:
                signal.setitimer(signal.ITIMER_REAL, random.uniform(1e-5, 6e-4))
                threads.run(kernel, [(0, 1), (1, 2), (2, 3)])
                signal.setitimer(signal.ITIMER_REAL, 0)
            except KeyboardInterrupt:
                interrupted += 1
            while True:   # a SIGINT sent just before the timer was stopped may still come
                try:
                    seen = len(finished)
                    break
                except KeyboardInterrupt:
                    interrupted += 1
            while True:
                try:
                    time.sleep(0.003)
                    break
                except KeyboardInterrupt:
                    pass
            late += len(finished) > seen
        print("interrupted", interrupted, "late", late, "busy", threads._busy, flush=True)
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          preexec_fn=default_signals)
    assert done.returncode == 0, done.stderr
    assert " late 0 busy 0" in done.stdout and "interrupted 0 " not in done.stdout, done.stdout


def test_a_signal_handlers_exception_while_waiting_is_raised_after_every_part():
    """A handler that raises (the CLI's SIGTERM and SIGHUP raise KeyboardInterrupt) while the caller waits for a
    worker's part: raised once that part is done, not while it still writes, and ``stop`` is called at once (a review
    found run returning while a worker ran on)."""
    done, stops = [], []
    claimed = threading.Event()

    def raising(signum, frame):
        raise RuntimeError("handler")

    def kernel(lo, hi):
        if lo:   # a worker's part: the signal comes while it runs and the caller waits for it
            claimed.set()
            time.sleep(0.3)
            done.append(lo)
        else:
            assert claimed.wait(10)
            threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGUSR1)).start()

    before = signal.signal(signal.SIGUSR1, raising)
    try:
        with pytest.raises(RuntimeError, match="handler"):
            threads.run(kernel, [(0, 1), (1, 2)], stop=lambda: stops.append(len(done)))
    finally:
        signal.signal(signal.SIGUSR1, before)
    assert done == [1] and stops == [0] and threads._busy == 0


def test_a_ctrl_c_stops_kernels_that_take_blocks(default_sigint):
    """With Python's own SIGINT handler (it raises KeyboardInterrupt once the call ends), a held Ctrl-C calls ``stop``
    at once: kernels that take their work in blocks (evolve_many's loop) stop within a block, not after the rest."""
    blocks, stopped = iter(range(200)), []
    taken = []

    def kernel(lo, hi):
        for b in blocks:
            if stopped:
                return
            taken.append(b)
            if b == 5:
                threading.Timer(0.0, os.kill, (os.getpid(), signal.SIGINT)).start()
            time.sleep(0.01)

    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with pytest.raises(KeyboardInterrupt):
        threads.run(kernel, [(0, 1), (1, 2)], stop=lambda: stopped.append(True))
    assert 6 <= len(taken) <= 12 and threads._busy == 0
