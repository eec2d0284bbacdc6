#!/bin/sh
# The rig's samples from host a to host b across `dicstream link` on a starved CPU: two network
# and mount namespaces made here (private /dev/shm and iceoryx2 folders, a veth pair at
# 10.84.0.1 and .2, nothing sent anywhere else), a's rig publishing rig/state at PUBLISH_HZ
# (500) for SECONDS_RUN (20) s, b's `dicstream tap rig/state` reading them; every process of
# both hosts on CPU (1), with HOGS (1) busy loops on that CPU. Prints what a's link sent and
# dropped, what b's link received and counted lost, and what b's reader got (docs/link.md's
# figures of `Drop` against `Block`). Run by hand, as root, with a dicstream built with
# `--features link` (DICSTREAM names another binary):
#
#   tests/starved_link.sh
set -eu
BIN=$(realpath "${DICSTREAM:-target/release/dicstream}")
SECONDS_RUN=${SECONDS_RUN:-20}
HZ=${PUBLISH_HZ:-500}
CPU=${CPU:-1}
HOGS=${HOGS:-1}
WORK=$(mktemp -d /tmp/dicstream-starved.XXXXXX)
INSTANCE=starved_$$
. "$(dirname "$0")/hosts.sh"
# On CPU only; in the background, the command in place of this subshell (a signal reaches it).
on_cpu() { pid=$1; shift; in_host "$pid" taskset -c "$CPU" "$@"; }
bg_on_cpu() { pid=$1; shift; exec nsenter --net=/proc/"$pid"/ns/net --mount=/proc/"$pid"/ns/mnt taskset -c "$CPU" "$@"; }
A=$(host 256m)
B=$(host 256m)
HOGPIDS=""
trap 'kill $A $B $HOGPIDS 2>/dev/null || true' EXIT
sleep 1
wire_up "$A" "$B" 84
echo "a-secret" >"$WORK/a.pw"; echo "b-secret" >"$WORK/b.pw"; echo "b:b-secret" >"$WORK/peers"
cat >"$WORK/a.toml" <<E2
[link]
listen = ["tcp/10.84.0.1:7447"]
user = "a"
password_file = "$WORK/a.pw"
peers_file = "$WORK/peers"
services = [{ name = "rig/state", direction = "out" }]
E2
cat >"$WORK/b.toml" <<E2
[link]
connect = ["tcp/10.84.0.1:7447"]
user = "b"
password_file = "$WORK/b.pw"
services = [{ name = "rig/state", direction = "in" }]
E2
bg_on_cpu $A "$BIN" link --json --instance $INSTANCE --config "$WORK/a.toml" >"$WORK/link_a.json" 2>"$WORK/link_a.log" &
LA=$!
bg_on_cpu $B "$BIN" link --json --instance $INSTANCE --config "$WORK/b.toml" >"$WORK/link_b.json" 2>"$WORK/link_b.log" &
LB=$!
while ! grep -q "a peer subscribes" "$WORK/link_a.log"; do sleep 0.2; done
bg_on_cpu $B "$BIN" tap rig/state --json --instance $INSTANCE --seconds $((SECONDS_RUN + 6)) >"$WORK/tap_b.json" 2>"$WORK/tap_b.log" &
TAP=$!
sleep 1
for k in $(seq 1 "$HOGS"); do taskset -c "$CPU" sh -c 'while :; do :; done' & HOGPIDS="$HOGPIDS $!"; done
on_cpu $A "$BIN" rig --instance $INSTANCE --test uniaxial --specimen homogeneous --stretch 1.5 --rate 0.01 \
    --publish-hz $HZ --duration-s $SECONDS_RUN >"$WORK/rig.out" 2>"$WORK/rig.log" || true
kill $HOGPIDS 2>/dev/null || true; HOGPIDS=""
wait $TAP || true
kill -TERM $LB; wait $LB || true
kill -TERM $LA; wait $LA || true
echo "work: $WORK"
python3 - "$WORK" <<'PY'
import json, sys
w = sys.argv[1]
a = json.load(open(f"{w}/link_a.json")); b = json.load(open(f"{w}/link_b.json"))
print("a out rig/state:", a["out"]["rig/state"])
print("b in rig/state:", b["in"]["rig/state"])
t = json.load(open(f"{w}/tap_b.json"))
print("tap on b:", {k: t[k] for k in ("received","drops","first_id","last_id","latency_us")})
PY
echo "gaps b's link reported: $(grep -c "lost by the link" "$WORK/link_b.log" || true)"
