# Sourced by tests/split_run.sh and tests/starved_link.sh: a "host" is a network and a mount
# namespace of its own, held by a sleep, with loopback up and private tmpfs /dev/shm, iceoryx2
# and owner folders (of SIZE each), so that two instances of the same name share nothing but
# the veth pair the script makes between them. Nothing is sent to any address outside them.

# Starts a host; prints the pid that holds its namespaces.
host() {
    unshare --net --mount --propagation private sh -c '
        mkdir -p /tmp/iceoryx2 /tmp/dicstream-owners
        for d in /dev/shm /tmp/iceoryx2 /tmp/dicstream-owners; do
            mount -t tmpfs -o size='"$1"' tmpfs "$d"; done
        ip link set lo up; exec sleep 3600' >/dev/null 2>&1 &
    echo $!
}

# Runs a command in the host held by pid $1.
in_host() {
    pid=$1
    shift
    nsenter --net=/proc/"$pid"/ns/net --mount=/proc/"$pid"/ns/mnt "$@"
}

# Joins the hosts held by $1 and $2 by a veth pair, $1 at 10.$3.0.1/24, $2 at 10.$3.0.2/24.
wire_up() {
    in_host "$1" ip link add va type veth peer name vb netns "$2"
    in_host "$1" ip addr add 10."$3".0.1/24 dev va
    in_host "$1" ip link set va up
    in_host "$2" ip addr add 10."$3".0.2/24 dev vb
    in_host "$2" ip link set vb up
}
