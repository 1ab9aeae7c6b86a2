"""Long calls release the GIL: another Python thread makes progress during `simulate`."""

import threading
import time

import dit_garment as dg


def test_another_thread_runs_while_simulate_does():
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        started = time.perf_counter()
        dg.simulate(frames=20)
        elapsed = time.perf_counter() - started
        during = ticks
    finally:
        done.set()
        counter.join()
    # With the GIL held for the whole call the counter could not tick at all while it ran;
    # released, it ticks about once a millisecond (at least a tenth of that on a busy machine).
    assert elapsed > 0.05, elapsed
    assert during > elapsed * 100, (during, elapsed)
