"""The stability suite: every probe of probes.py in its own process, under a time and an
address-space limit, so that a crash (a signal), a hang (the time limit) or a runaway allocation
is reported as such, naming the probe, instead of taking the test run down with it.

Run by CTest (stability_tests) with SDNATIVE_PATH naming the directory of the built module, under
the interpreter sdnative is built for (/usr/bin/python3: NumPy 1.x).
"""
import os
import resource
import signal
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import probes  # noqa: E402  (lists the probes; sdnative is imported by the probe processes only)

# Seconds per probe: the slowest takes about 5 s on these 2-core machines, shared.
TIME_LIMIT = 60
# Address space per probe: above the 4 GiB a call may allocate (sdnative.MAX_CALL_BYTES), below
# what would push the shared machine into the kernel's OOM killer.
MEMORY_LIMIT = 12 << 30


def limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


@pytest.mark.parametrize("name", probes.NAMES)
def test_probe(name):
    command = [sys.executable, os.path.join(HERE, "probes.py"), name]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=TIME_LIMIT, preexec_fn=limit_memory)
    except subprocess.TimeoutExpired:
        pytest.fail(f"probe {name} hung: no result within {TIME_LIMIT} s")
    output = (done.stdout + done.stderr)[-6000:]
    if done.returncode < 0:
        pytest.fail(f"probe {name} crashed: killed by {signal.Signals(-done.returncode).name}\n{output}")
    if done.returncode == probes.SKIP:
        pytest.skip(f"probe {name}: {done.stderr.strip()}")
    assert done.returncode == 0, f"probe {name} failed (exit {done.returncode}):\n{output}"
