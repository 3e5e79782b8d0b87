"""The GIL is released during a solve, and Ctrl-C stops it with
KeyboardInterrupt, leaving the interpreter able to solve again. Each case
runs in its own interpreter, so that the SIGINT cannot reach pytest."""

import os
import subprocess
import sys
import textwrap

from conftest import PLAZA, SOURCE_DIR

# A long solve of short Ceres solves: incremental, re-solved after every
# measurement (over a minute on Plaza 1; the iterations take milliseconds).
LONG = dict(incremental_every=1, incremental_lag=30)


def python(script):
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)],
                          capture_output=True, text=True, timeout=300,
                          cwd=SOURCE_DIR, env=dict(os.environ), check=False)


def test_ctrl_c_raises_keyboard_interrupt_and_the_interpreter_goes_on():
    done = python(f"""
        import os, signal, threading, time
        import rffslam
        dataset = rffslam.read_dataset({str(PLAZA)!r})
        threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()
        start = time.monotonic()
        try:
            rffslam.solve(dataset, **{LONG!r})
            print("not interrupted")
        except KeyboardInterrupt:
            print("interrupted after", time.monotonic() - start)
        result = rffslam.solve(dataset, max_iterations=2, prior="wnoa")
        print("then solved", len(result.times))
    """)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("interrupted after"), done.stdout
    assert float(lines[0].split()[-1]) < 10
    assert lines[1].startswith("then solved")


def test_other_threads_run_during_a_solve():
    done = python(f"""
        import threading, time
        import rffslam
        ticks = 0
        running = True
        def count():
            global ticks
            while running:
                ticks += 1
                time.sleep(0.001)
        dataset = rffslam.read_dataset({str(PLAZA)!r})
        thread = threading.Thread(target=count)
        thread.start()
        time.sleep(0.05)
        before = ticks
        start = time.monotonic()
        rffslam.solve(dataset, prior="wnoa")
        seconds = time.monotonic() - start
        during = ticks - before
        running = False
        thread.join()
        print(during, seconds)
    """)
    assert done.returncode == 0, done.stderr
    during, seconds = done.stdout.split()
    # With the GIL held the thread could not tick during the solve; released,
    # it ticks about once a millisecond.
    assert int(during) > max(5, 0.1 * float(seconds) * 1000), done.stdout
