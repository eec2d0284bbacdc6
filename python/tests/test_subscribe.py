"""``dicstream.subscribe`` against a live simulated bench (a camera and a correlator started by
the tests, stopped in teardown whatever the outcome): a field read from Python is the one
``dicstream tap`` reads, the numpy views are the shared memory itself (no copy), views release
their samples, and the layouts match the C header generated from the same description."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dicstream
from conftest import REPO, binary
from live import Bench, unique_instance

WAIT_S = 20  # the longest wait for one sample of a running bench (a hang guard, not a figure)


@pytest.fixture(scope="module")
def bench():
    bench = Bench(unique_instance("pysub"))
    try:
        yield bench
    finally:
        bench.stop()


def mean_gradient(nodes):
    """Mean du/dx, du/dy, dv/dx, dv/dy of the ok nodes, as tap computes it (in f64)."""
    ok = nodes[nodes["status"] == dicstream.NODE_STATUS["ok"]]
    return [float(ok[c].astype("f8").mean()) for c in ("du_dx", "du_dy", "dv_dx", "dv_dy")]


def test_a_field_read_from_python_is_the_one_tap_reads(bench):
    fields = dicstream.subscribe("fields", instance=bench.instance, timeout=WAIT_S)
    seen = {}

    def read_one():
        field = next(fields)
        seen[field.frame_id] = {
            "checksum": field.nodes_checksum(),
            "mean_gradient": mean_gradient(field.nodes),
            "u_mean_px": field.u_mean_px,
            "valid_nodes": field.valid_nodes,
            "nodes": field.nodes.size,
        }

    read_one()  # subscribed before the tap starts: every field the tap sees, Python sees
    tap = subprocess.Popen(
        [str(binary()), "tap", "fields", "--json", "--count", "3", "--instance", bench.instance],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        while tap.poll() is None:
            read_one()
        out, err = tap.communicate(timeout=WAIT_S)
    finally:
        if tap.poll() is None:
            tap.kill()
    assert tap.returncode == 0, err
    last = json.loads(out)["last"]
    while last["frame_id"] not in seen:
        read_one()  # the tap's last field may come to Python after the tap ended
    mine = seen[last["frame_id"]]
    assert mine["checksum"] == last["nodes_checksum"]
    assert mine["valid_nodes"] == last["valid_nodes"] and mine["nodes"] == last["nodes"]
    assert mine["u_mean_px"] == last["u_mean_px"]
    # The node values read through Python's dtype, averaged as tap does.
    tap_gradient = [last["mean_gradient"][k] for k in ("du_dx", "du_dy", "dv_dx", "dv_dy")]
    assert mine["mean_gradient"] == pytest.approx(tap_gradient, rel=1e-9, abs=1e-12)
    assert any(abs(g) > 0 for g in tap_gradient), "a uniaxial field has a gradient"


def mapping_of(address):
    """The /proc/self/maps line of the mapping holding ``address``."""
    for line in Path("/proc/self/maps").read_text().splitlines():
        start, end = (int(a, 16) for a in line.split()[0].split("-"))
        if start <= address < end:
            return line
    raise AssertionError(f"{address:#x} is in no mapping of this process")


@pytest.mark.parametrize("service, payload", [("fields", "nodes"), ("frames", "pixels")])
def test_views_are_the_shared_memory_itself(bench, service, payload):
    sample = next(dicstream.subscribe(service, instance=bench.instance, timeout=WAIT_S))
    view = getattr(sample, payload)
    address = view.__array_interface__["data"][0]
    # The array's data is where iceoryx2 put the payload, in the instance's shared memory.
    assert address == sample.payload_address
    mapping = mapping_of(address)
    assert mapping.split()[-1].startswith(f"/dev/shm/{bench.instance}_"), mapping
    header = sample.header.__array_interface__["data"][0]
    assert mapping_of(header) == mapping
    # A second view of the same sample is the same memory; views are read-only.
    assert getattr(sample, payload).__array_interface__["data"][0] == address
    assert not view.flags.writeable
    with pytest.raises(ValueError):
        view.flat[0] = view.flat[0]
    # The sample object is the views' owner.
    base = view
    while isinstance(base, np.ndarray):
        base = base.base
    assert base is sample
    if service == "frames":
        assert view.shape == (sample.height_px, sample.width_px) and view.dtype == np.uint16
    else:
        assert view.shape == (sample.mesh_rows, sample.mesh_cols)
        assert set(view.dtype.names) >= {"x_px", "u_px", "exx", "status", "dv_dy"}


def test_views_hold_their_samples_and_release_them(bench):
    fields = dicstream.subscribe("fields", instance=bench.instance, timeout=WAIT_S)
    # Views alone (their sample objects dropped) hold the samples: one more cannot be taken.
    held = [next(fields).nodes for _ in range(fields.max_borrowed)]
    with pytest.raises(ValueError, match=r"samples are held already \(max_borrowed\)"):
        next(fields)
    del held
    # Released, the stream flows for many more samples than the queue and borrows hold.
    kept, last_frame = [], -1
    for _ in range(3 * (fields.max_borrowed + fields.queue_size)):
        field = next(fields)
        assert field.frame_id > last_frame
        last_frame = field.frame_id
        kept.append(field.nodes)
        kept = kept[-(fields.max_borrowed - 1):]  # hold at most one less than allowed
        del field


def test_layouts_match_the_generated_c_header():
    header = (REPO / "wire" / "include" / "dicstream_wire.h").read_text()
    asserts = re.findall(r"offsetof\(Dicstream(\w+), (\w+)\) == (\d+)", header)
    sizes = dict(re.findall(r"sizeof\(Dicstream(\w+)\) == (\d+)", header))
    dtypes = dicstream.layouts()
    assert set(dtypes) == set(sizes)
    for name, dtype in dtypes.items():
        assert dtype.itemsize == int(sizes[name]), name
    assert len(asserts) > 50
    for layout, field, offset in asserts:
        assert dtypes[layout].fields[field][1] == int(offset), f"{layout}.{field}"
    assert f"#define DICSTREAM_LAYOUT_VERSION {dicstream.LAYOUT_VERSION}u" in header


def test_bad_service_and_timeout_are_clear_errors():
    with pytest.raises(ValueError, match='unknown service "nope": expected one of frames, fields'):
        dicstream.subscribe("nope", instance=unique_instance("nope"))
    with pytest.raises(ValueError, match="timeout -1"):
        dicstream.subscribe("fields", instance=unique_instance("neg"), timeout=-1)
    idle = dicstream.subscribe("rig/state", instance=unique_instance("idle"), timeout=0.2)
    with pytest.raises(TimeoutError, match="no rig/state sample on instance"):
        next(idle)


@pytest.mark.parametrize("script", ["live_mean_strain.py", "fields_to_csv.py"])
def test_examples_read_live_fields(bench, script, tmp_path):
    out = tmp_path / "fields.csv"
    args = [sys.executable, str(REPO / "examples" / "python" / script), "--instance",
            bench.instance, "--count", "3", "--timeout-s", str(WAIT_S)]
    if script == "fields_to_csv.py":
        args += ["--out", str(out)]
    done = subprocess.run(args, capture_output=True, text=True, timeout=3 * WAIT_S)
    assert done.returncode == 0, done.stderr
    if script == "fields_to_csv.py":
        rows = out.read_text().splitlines()
        assert len(rows) == 4 and rows[0].startswith("frame_id,"), rows
        assert all(len(r.split(",")) == len(rows[0].split(",")) for r in rows)
    else:
        lines = [l for l in done.stdout.splitlines() if l.startswith("frame")]
        assert len(lines) == 3 and "exx" in lines[0] and "log strain" in lines[0], done.stdout
