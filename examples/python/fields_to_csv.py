"""A crappy-style block: a loop that reads the live ``fields`` and writes one CSV row a field.

Like a block of crappy (the open live-testing framework), it has ``prepare`` (open the
subscription and the file), ``loop`` (called again and again: take what came, write it) and
``finish`` (close). Each row: the frame, its capture time, the valid nodes, the header's mean
displacement and gauge strains (the correlator's control gauge, log strain) and the mean
strains of the ok nodes, computed on the shared-memory view (no copy).

    python examples/python/fields_to_csv.py --instance demo --out fields.csv --count 100
"""

import argparse
import csv
import sys

import dicstream

OK = dicstream.NODE_STATUS["ok"]
# The header's gauge holds the strains of every measure, indexed by its code.
LOG = dicstream.STRAIN_MEASURES["log"]

COLUMNS = [
    "frame_id", "t_capture_ns", "valid_nodes", "nodes", "u_mean_px", "v_mean_px",
    "gauge_log_exx", "gauge_log_eyy", "gauge_log_exy", "nodes_mean_exx", "nodes_mean_eyy",
    "nodes_mean_exy",
]


class FieldsToCsv:
    def __init__(self, out, instance=None, timeout_s=5.0):
        self.out, self.instance, self.timeout_s = out, instance, timeout_s
        self.rows = 0

    def prepare(self):
        self.fields = dicstream.subscribe("fields", instance=self.instance, timeout=self.timeout_s)
        self.file = open(self.out, "w", newline="")
        self.writer = csv.writer(self.file)
        self.writer.writerow(COLUMNS)

    def loop(self):
        field = next(self.fields)
        nodes = field.nodes
        ok = nodes[nodes["status"] == OK]
        gauge = field.gauge[LOG]
        means = [float(ok[c].mean(dtype="f8")) if ok.size else float("nan") for c in ("exx", "eyy", "exy")]
        self.writer.writerow([
            field.frame_id, field.t_capture_ns, field.valid_nodes, nodes.size, field.u_mean_px,
            field.v_mean_px, float(gauge["exx"]), float(gauge["eyy"]), float(gauge["exy"]), *means,
        ])
        self.file.flush()
        self.rows += 1

    def finish(self):
        self.file.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instance", default=None, help="instance name (default: the CLI's)")
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--count", type=int, default=None, help="stop after this many fields")
    parser.add_argument("--timeout-s", type=float, default=5.0, help="stop after this long without a field")
    args = parser.parse_args()

    block = FieldsToCsv(args.out, args.instance, args.timeout_s)
    block.prepare()
    try:
        while args.count is None or block.rows < args.count:
            block.loop()
    except TimeoutError as e:
        print(f"fields_to_csv: {e}; stopping", file=sys.stderr)
    finally:
        block.finish()
    print(f"fields_to_csv: {block.rows} rows in {args.out}")


if __name__ == "__main__":
    main()
