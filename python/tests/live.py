"""A live bench for the tests of ``subscribe``: a simulated camera (``dicstream producer``)
and a correlator (``dicstream correlator``) on an instance of the test's own, started as
processes and stopped (SIGTERM, then SIGKILL) whatever the test's outcome, with the instance's
files removed after them (as the Rust tests' ``testkit::TestInstance``)."""

import gc
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

from conftest import binary

# Small frames at a modest rate: the correlator keeps up on one thread while the other core builds.
SIDE_PX = 256
FPS = 20
READY_WAIT_S = 60
STOP_WAIT_S = 10


class Child:
    """A dicstream process whose stderr is collected by a thread (lines, for readiness)."""

    def __init__(self, name, args):
        self.name = name
        self.process = subprocess.Popen(
            [str(binary()), *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        self.lines = []
        self.changed = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.process.stderr:
            with self.changed:
                self.lines.append(line.rstrip("\n"))
                self.changed.notify_all()
        with self.changed:
            self.changed.notify_all()

    def wait_for(self, needle, timeout_s=READY_WAIT_S):
        deadline = time.monotonic() + timeout_s
        with self.changed:
            while True:
                if any(needle in line for line in self.lines):
                    return
                left = deadline - time.monotonic()
                if left <= 0 or self.process.poll() is not None:
                    raise AssertionError(
                        f"{self.name}: no line with {needle!r} (exit {self.process.poll()}):\n"
                        + "\n".join(self.lines)
                    )
                self.changed.wait(min(left, 0.5))

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def remove_instance_files(instance):
    """Every file of the instance in /dev/shm and iceoryx2's folder (its prefix ``NAME_``)."""
    prefix = f"{instance}_"
    for root in (Path("/dev/shm"), Path("/tmp/iceoryx2")):
        if root.is_dir():
            for path in root.rglob(f"{prefix}*"):
                if path.is_file():
                    path.unlink(missing_ok=True)


class Bench:
    """Correlator and camera on ``instance``; the camera runs until stopped."""

    def __init__(self, instance):
        self.instance = instance
        remove_instance_files(instance)
        self.children = []
        correlator = self.start(
            "correlator", ["correlator", "--instance", instance, "--threads", "1"]
        )
        correlator.wait_for("correlator: ready")
        camera = self.start(
            "producer",
            [
                "producer", "--instance", instance, "--scenario", "uniaxial", "--width",
                str(SIDE_PX), "--height", str(SIDE_PX), "--fps", str(FPS), "--frames", "1000000",
                "--threads", "1",
            ],
        )
        camera.wait_for("producer: ready")

    def start(self, name, args):
        child = Child(name, args)
        self.children.append(child)
        return child

    def stop(self):
        for child in reversed(self.children):
            child.stop()
        gc.collect()  # the tests' own subscriptions (nodes) go before their files do
        remove_instance_files(self.instance)


def unique_instance(test):
    """An instance name of this process and test (as testkit's: ``t<pid>_<test>``)."""
    return f"t{os.getpid()}_{test}"[:32]
