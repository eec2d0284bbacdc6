"""A live consumer: prints each measured field's mean strain as the correlator publishes it.

The nodes are a numpy view of the field in shared memory (no copy); the mean is over the
nodes whose status is ok, of the strain measure the field's header names (``strain_measure``,
the correlator's ``--strain``).

    dicstream run --instance demo &          # or a producer and a correlator on instance demo
    python examples/python/live_mean_strain.py --instance demo
"""

import argparse

import dicstream

OK = dicstream.NODE_STATUS["ok"]
MEASURE_NAMES = {code: name for name, code in dicstream.STRAIN_MEASURES.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instance", default=None, help="instance name (default: the CLI's)")
    parser.add_argument("--count", type=int, default=None, help="stop after this many fields")
    parser.add_argument("--timeout-s", type=float, default=None, help="give up after this long without a field")
    args = parser.parse_args()

    fields = dicstream.subscribe("fields", instance=args.instance, timeout=args.timeout_s)
    for seen, field in enumerate(fields, start=1):
        nodes = field.nodes
        ok = nodes[nodes["status"] == OK]
        if ok.size:
            means = {c: float(ok[c].mean(dtype="f8")) for c in ("exx", "eyy", "exy")}
            strain = "  ".join(f"{c} {v:+.4e}" for c, v in means.items())
        else:
            strain = "no valid node"
        print(
            f"frame {field.frame_id:6d}  {ok.size:4d}/{nodes.size:4d} nodes  {strain}  "
            f"({MEASURE_NAMES.get(field.strain_measure, '?')} strain)",
            flush=True,
        )
        del nodes, ok, field  # the sample goes back to the correlator
        if args.count is not None and seen >= args.count:
            break


if __name__ == "__main__":
    main()
