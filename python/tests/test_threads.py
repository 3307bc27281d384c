"""Threads: long calls release the GIL, and concurrent queries give the
answers of serial ones. No test depends on which thread the scheduler
runs first."""

import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from conftest import point_of


def directions(n, seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 3)), rng.normal(size=(n, 3))


def test_concurrent_queries_agree_with_serial_ones(log_model):
    points = [[0.1 * k - 0.3, 0.05 * k] for k in range(8)]
    inputs = [directions(20_000, k) for k in range(8)]
    serial = [log_model.eval(x, wi, wo) for x, (wi, wo) in zip(points, inputs)]
    material = log_model.material(point_of(log_model, "000-metal-copper-r0.18"))
    shared = directions(20_000, 99)
    expected = material.eval(*shared)
    with ThreadPoolExecutor(8) as pool:
        concurrent = list(pool.map(lambda k: log_model.eval(points[k], *inputs[k]), range(8)))
        again = list(pool.map(lambda _: material.eval(*shared), range(8)))
    for a, b in zip(serial, concurrent):
        assert np.array_equal(a, b)
    for a in again:
        assert np.array_equal(a, expected)


def test_a_long_eval_lets_python_threads_run(raw_model):
    """While one thread is inside a long eval, another runs Python code to
    its end. Python asks a thread holding the GIL to let go only once per
    switch interval; with the interval far beyond the eval's length, the
    other thread can run during the eval only if the eval releases the GIL.
    Had it held it, the eval would end first. Once the other thread has the
    GIL it keeps it to its end, so the order is fixed either way."""
    wi, wo = directions(2_000_000, 5)
    events = []
    ready = threading.Event()

    def python_work():
        ready.wait()  # blocks, without the GIL
        total = 0
        for k in range(200_000):
            total += k
        events.append("python done")

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    try:
        other = threading.Thread(target=python_work)
        other.start()
        ready.set()
        raw_model.eval([0.0, 0.0], wi, wo)
        events.append("eval done")
        other.join()
    finally:
        sys.setswitchinterval(interval)
    assert events == ["python done", "eval done"]
