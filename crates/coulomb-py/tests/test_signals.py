"""Ctrl-C during `Simulation.run(n)` (issue 55): the signals are checked between steps, so a
SIGINT raises KeyboardInterrupt after the step in progress instead of after the n-th step."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time


def test_run_raises_keyboard_interrupt_between_steps():
    # in a child interpreter, so that the signal reaches only it
    code = textwrap.dedent(
        """
        import signal, sys, time
        # Python's own SIGINT handler, also where the child inherits SIGINT ignored (a
        # background job of a non-interactive shell): KeyboardInterrupt is what is tested
        signal.signal(signal.SIGINT, signal.default_int_handler)
        from coulomb.granular import Simulation
        sim = Simulation("box", beads=200, seed=1)
        print("ready", flush=True)
        start = time.monotonic()
        try:
            sim.run(10_000_000)
        except KeyboardInterrupt:
            print("interrupted", sim.steps_done, round(time.monotonic() - start, 3), flush=True)
            sys.exit(0)
        print("finished", flush=True)
        sys.exit(1)
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        os.kill(child.pid, signal.SIGINT)
        out, err = child.communicate(timeout=120)
    finally:
        # never leave the child simulating when an assertion or the timeout fails the test
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 0, (out, err)
    words = out.split()
    assert words[0] == "interrupted", (out, err)
    # stopped after some steps, far from the ten million asked for
    assert 0 < int(words[1]) < 10_000_000
