#!/bin/sh
# The split run of docs/link.md ("Two hosts, step by step") run end to end on one machine: two
# network and mount namespaces made here (private /dev/shm and iceoryx2 folders, a veth pair at
# 10.83.0.1 and .2, nothing sent anywhere else), the rig's part of the bench on host a, the
# camera, correlator and identifier on host b, each started by its own `dicstream run` with
# `[link] start_with_run`; then the same configuration on one host, and their verdicts and
# figures side by side. Too slow for CI (two whole campaigns): run by hand, as root, with a
# dicstream built with `--features link`:
#
#   cargo build --release --features link
#   tests/split_run.sh                                          # the default campaign
#   tests/split_run.sh examples/configs/strain_equibiaxial.toml # strain control's |ρ − 1|
#
# The configuration's own `[run]` keys are kept (processes and dashboard are added), its
# `[link]` must be absent. Prints each run's last lines and, for a strain-controlled test, the
# worst |ln λy / ln λx − 1| of the fields while loading beyond λ 1.05 (docs/figures.md's
# figure), from each run's frames.csv. Leaves its folder (printed) for a look.
set -eu

# Absolute: nsenter --mount starts the command at the namespace's root.
BIN=$(realpath "${DICSTREAM:-target/release/dicstream}")
BASE=${1:-}
WORK=$(mktemp -d /tmp/dicstream-split.XXXXXX)
INSTANCE=split_$$
echo "split run in $WORK (configuration: ${BASE:-the default})"

. "$(dirname "$0")/hosts.sh"
A=$(host 2g)
B=$(host 2g)
trap 'kill $A $B 2>/dev/null || true' EXIT
sleep 1
wire_up "$A" "$B" 83

echo "rig-pc-secret" >"$WORK/rig-pc.password"
echo "camera-pc-secret" >"$WORK/camera-pc.password"
echo "camera-pc:camera-pc-secret" >"$WORK/link.peers"

# The configuration with `[run]` keys added (inside its own [run] if it has one).
with_run_keys() {
    if [ -n "$BASE" ]; then cat "$BASE"; fi | awk -v add="$1" '
        /^\[run\]/ { print; print add; done = 1; next }
        { print }
        END { if (!done) { print "[run]"; print add } }'
}

with_run_keys 'processes = ["rig"]
dashboard = "off"' >"$WORK/a.toml"
cat >>"$WORK/a.toml" <<EOF
[link]
listen = ["tcp/10.83.0.1:7447"]
user = "rig-pc"
password_file = "$WORK/rig-pc.password"
peers_file = "$WORK/link.peers"
start_with_run = true
services = [
  { name = "rig/state", direction = "out" },
  { name = "specimen", direction = "out" },
  { name = "fields", direction = "in" },
  { name = "identification", direction = "in" },
]
EOF
with_run_keys 'processes = ["producer", "correlator", "identifier"]
dashboard = "off"' >"$WORK/b.toml"
cat >>"$WORK/b.toml" <<EOF
[link]
connect = ["tcp/10.83.0.1:7447"]
user = "camera-pc"
password_file = "$WORK/camera-pc.password"
start_with_run = true
services = [
  { name = "rig/state", direction = "in" },
  { name = "specimen", direction = "in" },
  { name = "fields", direction = "out" },
  { name = "identification", direction = "out" },
]
EOF
with_run_keys 'dashboard = "off"' >"$WORK/one.toml"

started=$(date +%s)
in_host "$A" "$BIN" run --quiet --config "$WORK/a.toml" --instance "$INSTANCE" \
    --out "$WORK/a" >"$WORK/a.stdout" 2>"$WORK/a.stderr" &
RUN_A=$!
sleep 2
in_host "$B" "$BIN" run --quiet --config "$WORK/b.toml" --instance "$INSTANCE" \
    --out "$WORK/b" >"$WORK/b.stdout" 2>"$WORK/b.stderr" &
RUN_B=$!
code_a=0
wait $RUN_A || code_a=$?
code_b=0
wait $RUN_B || code_b=$?
echo "split run: $(($(date +%s) - started)) s"
code_one=0
"$BIN" run --quiet --config "$WORK/one.toml" --instance "one_$$" --out "$WORK/one" \
    >"$WORK/one.stdout" 2>"$WORK/one.stderr" || code_one=$?

for part in a b one; do
    eval code=\$code_$part
    echo "== $part: exit code $code"
    cat "$WORK/$part.stdout"
    grep -E "^run: (completed|failed)|^run: exit" "$WORK/$part.stderr" || true
done

python3 - "$WORK" <<'EOF'
import csv, json, math, sys
work = sys.argv[1]
for part in ["a", "b", "one"]:
    s = json.load(open(f"{work}/{part}/summary.json"))
    link = s.get("link") or {}
    print(f"{part}: ending {s['ending']}, exit code {s['exit_code']}, failure {s.get('failure')!r}, "
          f"fields {s['fields']}, link lost {link.get('lost')}")
    if not s.get("strain_target"):
        continue
    try:
        rows = list(csv.DictReader(open(f"{work}/{part}/frames.csv")))
    except FileNotFoundError:
        continue
    pairs = [(float(r["log_exx"]), float(r["log_eyy"])) for r in rows
             if r.get("log_exx") not in (None, "", "NaN") and r.get("log_eyy") not in (None, "", "NaN")]
    if not pairs:
        continue
    peak = max(range(len(pairs)), key=lambda k: max(pairs[k]))
    loading = [(x, y) for x, y in pairs[: peak + 1] if max(x, y) >= math.log(1.05)]
    if loading:
        worst = max(abs(y / x - 1.0) for x, y in loading if x != 0.0)
        print(f"{part}: |rho - 1| worst {worst:.4f} over {len(loading)} fields while loading "
              f"beyond λ 1.05")
EOF
