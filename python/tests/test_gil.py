"""Long calls release the GIL: a Python thread keeps running during them.

While one thread is inside a call that holds the GIL no other Python code
runs at all, so ticks of a counting thread stamped well inside the call
(not near its ends, where the interpreter may switch threads) show that the
GIL was released."""

import threading
import time

import numpy as np

import interslice


def ticks_inside(call):
    stamps = []
    stop = threading.Event()
    started = threading.Event()

    def count():
        started.set()
        n = 0
        while not stop.is_set():
            n += 1
            if n % 100 == 0:
                stamps.append(time.perf_counter())

    t = threading.Thread(target=count)
    t.start()
    started.wait()
    try:
        t0 = time.perf_counter()
        call()
        t1 = time.perf_counter()
    finally:
        stop.set()
        t.join()
    lo, hi = t0 + 0.25 * (t1 - t0), t1 - 0.25 * (t1 - t0)
    return sum(lo < s < hi for s in stamps), t1 - t0


def test_other_threads_run_during_evaluate_and_interpolate():
    image, labels, meta = interslice.phantom(size=128, seed=2)
    seg = np.roll(labels, 2, axis=0)
    sp = meta["spacing"]
    sparse = np.zeros_like(labels)
    sparse[:, :, ::4] = labels[:, :, ::4]

    # One call each: between two calls the interpreter may switch threads.
    def evaluate():
        interslice.evaluate(labels, seg, sp)

    def interpolate():
        interslice.interpolate(sparse, spacing=sp, method="shape-based")

    for call in (evaluate, interpolate):
        inside, took = ticks_inside(call)
        assert inside > 0, f"no Python ran during {call.__name__} ({took:.3f} s)"
