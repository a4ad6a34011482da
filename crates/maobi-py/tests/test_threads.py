"""Heavy calls release the GIL: two Python threads render at the same time, and a pure-Python
thread keeps running while a call is in maobi."""

import threading
import time

import numpy as np

import maobi


def test_two_threads_render_at_once_and_get_the_serial_results():
    rng = np.random.default_rng(1)
    jobs = []
    for _ in range(2):
        p = np.column_stack([rng.uniform(5, 55, 400), rng.uniform(5, 55, 400), rng.uniform(11, 20, 400), np.zeros(400), rng.uniform(0, 0.08, 400)])
        jobs.append(p)
    serial = [maobi.render_presses(p, 60.0, 512) for p in jobs]
    results = [None, None]
    both = threading.Barrier(2)

    def work(i):
        both.wait()
        results[i] = [maobi.render_presses(jobs[i], 60.0, 512) for _ in range(3)]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(2):
        assert all(np.array_equal(r, serial[i]) for r in results[i])


def test_a_python_thread_runs_while_maobi_works():
    # A pure-Python thread notes the time as it runs. Had the call kept the GIL, no note could
    # fall strictly inside it; released, the thread runs all along.
    notes = []
    stop = threading.Event()

    def note():
        while not stop.is_set():
            notes.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=note)
    t.start()
    try:
        time.sleep(0.01)
        t0 = time.perf_counter()
        maobi.write("永", size_px=256)
        t1 = time.perf_counter()
    finally:
        stop.set()
        t.join()
    inside = [x for x in notes if t0 < x < t1]
    assert len(inside) >= 5, f"{len(inside)} notes during a {t1 - t0:.3f} s call"
