//! Two hosts linked over Zenoh (`dicstream link`, feature `link`), on one machine without a
//! network: each "host" is a network namespace and a mount namespace of the test's own, with
//! its own `/dev/shm` and iceoryx2 folders (tmpfs), so the two instances, of the same name,
//! share nothing but the veth pair between them: the link is the only way from one to the
//! other. Nothing is sent to any address outside the namespaces; Zenoh's scouting is off.
//!
//! The samples are `fields` from a small publisher of the test's own (the test binary run
//! again inside a host, `helper_role`), received on the far host by another; the same
//! samples are also received on the publisher's host, so that the link's added latency is
//! measured against one host's in the same run (printed, never asserted).
//!
//! Where no namespace can be made (not root), each test says so and is skipped, except under
//! CI (`CI` set), where that is a failure.

#![cfg(feature = "link")]

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use testkit::{Proc, HANG_GUARD};
use wire::plain::{slice_bytes, value_bytes};
use wire::pubsub::{SlicePublisher, SliceSubscriber};
use wire::stats::Durations;
use wire::{services, FieldHeader, FieldNode};

const DICSTREAM: &str = env!("CARGO_BIN_EXE_dicstream");
/// The environment variable that makes this test binary a helper (`helper_role`).
const ROLE: &str = "DICSTREAM_LINK_TEST_ROLE";
const PORT: u16 = 7447;
/// Mesh of the published fields: 16 × 16 nodes (10 KiB a field).
const MESH_SIDE: u32 = 16;

/// A host: a network and mount namespace (held by a `sleep`) with loopback up and private
/// `/dev/shm`, iceoryx2 and owner folders; the processes started in it die with it.
struct Host {
    name: &'static str,
    holder: Proc,
    procs: Vec<Proc>,
}

impl Host {
    fn new(name: &'static str) -> Host {
        let mut holder = Command::new("unshare");
        holder.args([
            "--net",
            "--mount",
            "--propagation",
            "private",
            "sh",
            "-c",
            "set -e; mkdir -p /tmp/iceoryx2 /tmp/dicstream-owners; \
             for d in /dev/shm /tmp/iceoryx2 /tmp/dicstream-owners; do \
               mount -t tmpfs -o size=256m tmpfs $d; done; \
             ip link set lo up; echo host-ready >&2; exec sleep 3600",
        ]);
        let mut holder = Proc::spawn(&format!("{name}-ns"), holder);
        holder.wait_for_stderr("the host's namespaces", |l| l.contains("host-ready"));
        Host {
            name,
            holder,
            procs: Vec::new(),
        }
    }

    fn command(&self, program: &str, args: &[&str]) -> Command {
        let pid = self.holder.pid();
        let mut command = Command::new("nsenter");
        command
            .arg(format!("--net=/proc/{pid}/ns/net"))
            .arg(format!("--mount=/proc/{pid}/ns/mnt"))
            .arg(program)
            .args(args);
        command
    }

    /// Runs `sh -c script` in the host; panics on failure.
    fn sh(&self, script: &str) -> String {
        let out = self
            .command("sh", &["-c", script])
            .output()
            .expect("nsenter");
        assert!(out.status.success(), "{}: {script}: {out:?}", self.name);
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    fn spawn(&mut self, name: &str, command: Command) -> usize {
        self.procs
            .push(Proc::spawn(&format!("{}:{name}", self.name), command));
        self.procs.len() - 1
    }

    /// `dicstream link` with the configuration `config`, keeping its counts in `counts` if
    /// given.
    fn link(&mut self, instance: &str, config: &Path, counts: Option<&Path>) -> usize {
        let mut args = vec![
            "link",
            "--json",
            "--instance",
            instance,
            "--config",
            config.to_str().unwrap(),
        ];
        if let Some(counts) = counts {
            args.extend(["--counts-json", counts.to_str().unwrap()]);
        }
        let command = self.command(DICSTREAM, &args);
        self.spawn("link", command)
    }

    /// This test binary again, as the helper `role` (`helper_role`).
    fn helper(&mut self, role: &str, instance: &str, out: &Path, count: u64) -> usize {
        let exe = std::env::current_exe().unwrap();
        let mut command = self.command(
            exe.to_str().unwrap(),
            &["--exact", "helper_role", "--nocapture", "--test-threads=1"],
        );
        command
            .env(ROLE, role)
            .env("HELPER_INSTANCE", instance)
            .env("HELPER_OUT", out)
            .env("HELPER_COUNT", count.to_string());
        self.spawn(role, command)
    }

    fn proc(&mut self, index: usize) -> &mut Proc {
        &mut self.procs[index]
    }

    /// The TCP sockets listening in the host (`ss`), one local address per line.
    fn listening(&self) -> Vec<String> {
        self.sh("ss -Htln | awk '{print $4}'")
            .lines()
            .map(str::to_string)
            .collect()
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        for p in &mut self.procs {
            p.kill();
        }
        self.holder.kill();
    }
}

/// Joins `a` and `b` by a veth pair: `a` at 10.`net`.0.1/24, `b` at 10.`net`.0.2/24.
fn wire_up(a: &Host, b: &Host, net: u8) -> (String, String) {
    let (ip_a, ip_b) = (format!("10.{net}.0.1"), format!("10.{net}.0.2"));
    let (if_a, if_b) = (format!("v{net}{}", b.name), format!("v{net}{}", a.name));
    a.sh(&format!(
        "ip link add {if_a} type veth peer name {if_b} netns {} && \
         ip addr add {ip_a}/24 dev {if_a} && ip link set {if_a} up",
        b.holder.pid()
    ));
    b.sh(&format!(
        "ip addr add {ip_b}/24 dev {if_b} && ip link set {if_b} up"
    ));
    (ip_a, ip_b)
}

/// Whether namespaces can be made here; under CI they must.
fn namespaces_available(test: &str) -> bool {
    let probe = Command::new("unshare")
        .args(["--net", "--mount", "true"])
        .output();
    let ok = probe.as_ref().is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "{test}: cannot create network and mount namespaces (`unshare --net --mount`: \
             {probe:?})"
        );
        eprintln!("SKIPPED {test}: cannot create network and mount namespaces here ({probe:?})");
    }
    ok
}

/// The test's scratch folder (configurations, passwords, the helpers' results), removed on
/// drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new(instance: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("dicstream-link-{instance}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A `[link]` configuration: `user` with its password file, its endpoints and services.
fn link_config(scratch: &Scratch, user: &str, endpoints: &str, services: &str) -> PathBuf {
    let password = scratch.write(&format!("{user}.password"), &format!("{user}-secret\n"));
    let peers = scratch.path("peers");
    scratch.write(
        &format!("{user}.toml"),
        &format!(
            "[link]\n{endpoints}\nuser = \"{user}\"\npassword_file = \"{}\"\n\
             peers_file = \"{}\"\nservices = [{services}]\n",
            password.display(),
            peers.display()
        ),
    )
}

/// The peers a listening host lets in: the lab's hosts a and b (not the intruder).
fn write_peers(scratch: &Scratch) {
    scratch.write("peers", "host-a:host-a-secret\nhost-b:host-b-secret\n");
}

/// What a subscriber helper wrote: (id, checksum of the sample's bytes, latency ns) per
/// sample.
fn read_samples(path: &Path) -> Vec<(u64, u64, u64)> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|line| {
            let mut words = line.split(' ').map(|w| w.parse::<u64>().unwrap());
            (
                words.next().unwrap(),
                words.next().unwrap(),
                words.next().unwrap(),
            )
        })
        .collect()
}

/// Every id from 0 to `count - 1` was received by the receiving link (`json`), counted lost
/// by it, or declared skipped by the sending link (the ids missing in what the sending host's
/// instance gave it: on a loaded machine its queue of 8 fields overflows now and then, which
/// it cannot tell from a correlator's skipped frames); its host's reader missed at least what
/// the link lost (more when a burst after an outage overflows the reader's queue, a loss on
/// that host, not the link's).
fn assert_every_id_received_or_counted_lost(json: &serde_json::Value, count: u64, missing: u64) {
    let fields_in = &json["in"]["fields"];
    let (received, lost, skipped) = (
        fields_in["received"].as_u64().unwrap(),
        fields_in["lost"].as_u64().unwrap(),
        fields_in["skipped_by_sender"].as_u64().unwrap(),
    );
    assert_eq!(fields_in["first_id"], 0, "{json}");
    assert_eq!(fields_in["last_id"], count - 1, "{json}");
    assert_eq!(
        received + lost + skipped,
        count,
        "every id received, counted lost or declared skipped: {json}"
    );
    assert!(lost > 0, "the fault lost nothing? {json}");
    assert!(
        missing >= lost,
        "the reader missed {missing}, fewer than the link lost: {json}"
    );
}

/// The JSON a link printed at its exit (after SIGTERM).
fn stop_link(host: &mut Host, index: usize) -> serde_json::Value {
    let link = host.proc(index);
    link.signal(libc::SIGTERM);
    let (status, stdout, stderr) = link.wait();
    assert!(status.success(), "link: {status:?}\n{stderr}");
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("link --json ({e}): {stdout}"))
}

fn latency_line(label: &str, samples: &[(u64, u64, u64)]) -> (f64, f64) {
    let mut durations = Durations::new();
    for &(_, _, latency_ns) in samples {
        durations.record_ns(latency_ns);
    }
    let (median, p99) = (durations.median_ms(), durations.quantile_ms(0.99));
    println!(
        "latency of fields, {label}: median {:.3} ms, p99 {:.3} ms over {} samples",
        median,
        p99,
        samples.len()
    );
    (median, p99)
}

/// Two hosts a (10.`net`.0.1, listening, a service out) and b (connecting, the service in,
/// its link's counts in `counts_b`), each with its link started and a's link seeing b
/// subscribe.
struct Lab {
    instance: String,
    scratch: Scratch,
    a: Host,
    b: Host,
    link_a: usize,
    link_b: usize,
    config_a: PathBuf,
    counts_b: PathBuf,
}

impl Lab {
    /// The lab carrying `fields`.
    fn new(test: &str, net: u8) -> Lab {
        Lab::carrying(test, net, "fields")
    }

    fn carrying(test: &str, net: u8, service: &str) -> Lab {
        let instance = testkit::unique_instance(test);
        let scratch = Scratch::new(&instance);
        write_peers(&scratch);
        let (mut a, mut b) = (Host::new("a"), Host::new("b"));
        let (ip_a, _) = wire_up(&a, &b, net);
        let route = |direction| format!("{{ name = \"{service}\", direction = \"{direction}\" }}");
        let config_a = link_config(
            &scratch,
            "host-a",
            &format!("listen = [\"tcp/{ip_a}:{PORT}\"]"),
            &route("out"),
        );
        let config_b = link_config(
            &scratch,
            "host-b",
            &format!("connect = [\"tcp/{ip_a}:{PORT}\"]"),
            &route("in"),
        );
        let counts_b = scratch.path("counts_b.json");
        let link_a = a.link(&instance, &config_a, None);
        let link_b = b.link(&instance, &config_b, Some(&counts_b));
        a.proc(link_a)
            .wait_line(&format!("{service} out: a peer subscribes"));
        Lab {
            instance,
            scratch,
            a,
            b,
            link_a,
            link_b,
            config_a,
            counts_b,
        }
    }

    /// Starts a subscriber helper in `host` writing to `file`, waiting for it to be ready.
    fn subscriber(&mut self, on_b: bool, file: &str, count: u64) -> usize {
        let out = self.scratch.path(file);
        let host = if on_b { &mut self.b } else { &mut self.a };
        let index = host.helper("subscribe", &self.instance, &out, count);
        host.proc(index).wait_line("helper: subscribed");
        index
    }
}

#[test]
fn fields_cross_to_the_other_host_byte_identical_without_gaps() {
    if !namespaces_available("fields_cross") {
        return;
    }
    const COUNT: u64 = 600;
    let mut lab = Lab::new("link_cross", 77);
    // Each host listens where it was told and nowhere else.
    assert_eq!(lab.a.listening(), [format!("10.77.0.1:{PORT}")]);
    assert_eq!(lab.b.listening(), Vec::<String>::new());

    let sub_b = lab.subscriber(true, "b.txt", COUNT);
    let sub_a = lab.subscriber(false, "a.txt", COUNT);
    let sent = lab.scratch.path("sent.txt");
    let publisher = lab.a.helper("publish", &lab.instance.clone(), &sent, COUNT);
    for index in [publisher, sub_a] {
        let (status, _, stderr) = lab.a.proc(index).wait();
        assert!(status.success(), "{stderr}");
    }
    let (status, _, stderr) = lab.b.proc(sub_b).wait();
    assert!(status.success(), "{stderr}");
    let json_b = stop_link(&mut lab.b, lab.link_b);
    let json_a = stop_link(&mut lab.a, lab.link_a);

    let sent = read_samples(&sent);
    let (on_a, on_b) = (
        read_samples(&lab.scratch.path("a.txt")),
        read_samples(&lab.scratch.path("b.txt")),
    );
    assert_eq!(sent.len() as u64, COUNT);
    assert_eq!(on_a.len() as u64, COUNT, "one host: every sample");
    assert_eq!(on_b.len() as u64, COUNT, "across the link: every sample");
    for ((s, a), b) in sent.iter().zip(&on_a).zip(&on_b) {
        assert_eq!((s.0, s.1), (a.0, a.1), "one host: the same bytes");
        assert_eq!((s.0, s.1), (b.0, b.1), "across the link: the same bytes");
    }
    let fields_in = &json_b["in"]["fields"];
    assert_eq!(fields_in["received"], COUNT, "{json_b}");
    assert_eq!(fields_in["lost"], 0, "{json_b}");
    assert_eq!(fields_in["refused"], 0, "{json_b}");
    assert_eq!(json_a["out"]["fields"]["sent"], COUNT, "{json_a}");

    let (one_median, one_p99) = latency_line("one host", &on_a);
    let (link_median, link_p99) = latency_line("across the link (veth)", &on_b);
    println!(
        "added by the link: median {:.3} ms, p99 {:.3} ms",
        link_median - one_median,
        link_p99 - one_p99
    );
}

#[test]
fn a_peer_not_in_the_configuration_gets_nothing() {
    if !namespaces_available("intruder") {
        return;
    }
    let mut lab = Lab::new("link_intruder", 78);
    // A third host, wired to a, that knows a's address and the service but is not among the
    // peers a lets in.
    let mut c = Host::new("c");
    let (_, ip_c) = wire_up(&lab.a, &c, 79);
    c.sh(&format!(
        "ip route add 10.78.0.0/24 via 10.79.0.1 src {ip_c}"
    ));
    let intruder = link_config(
        &lab.scratch,
        "intruder",
        &format!("connect = [\"tcp/10.78.0.1:{PORT}\"]"),
        "{ name = \"fields\", direction = \"in\" }",
    );
    let link_c = c.link(&lab.instance, &intruder, None);
    let sub_c = c.helper(
        "subscribe",
        &lab.instance,
        &lab.scratch.path("c.txt"),
        u64::MAX,
    );
    c.proc(sub_c).wait_line("helper: subscribed");
    // a sees the intruder's attempts fail, and b's subscriber gets every sample meanwhile.
    let sub_b = lab.subscriber(true, "b.txt", 200);
    let publisher = lab.a.helper(
        "publish",
        &lab.instance.clone(),
        &lab.scratch.path("sent.txt"),
        200,
    );
    let (status, _, stderr) = lab.a.proc(publisher).wait();
    assert!(status.success(), "{stderr}");
    let (status, _, stderr) = lab.b.proc(sub_b).wait();
    assert!(status.success(), "{stderr}");
    c.proc(sub_c).signal(libc::SIGTERM);
    c.proc(sub_c).wait();
    let json_c = stop_link(&mut c, link_c);
    assert_eq!(read_samples(&lab.scratch.path("b.txt")).len(), 200);
    assert_eq!(
        read_samples(&lab.scratch.path("c.txt")).len(),
        0,
        "the intruder got samples"
    );
    assert_eq!(json_c["in"]["fields"]["received"], 0, "{json_c}");
}

/// What crossed from a to b while a fault happened.
struct Faulted {
    /// b's link's counts at its exit.
    json_b: serde_json::Value,
    /// Fields a's links sent, in all.
    sent_by_a: u64,
    /// Fields b's reader received, and the ids it missed.
    received_on_b: usize,
    missing_on_b: u64,
}

impl Lab {
    /// Publishes `count` fields on a at 200 Hz; once b has the first, `fault` (which returns
    /// the fields sent by a's links it stopped); after the last, stops b's reader and both
    /// links. Every field b received is byte-identical, and every id was received or counted
    /// lost by b's link.
    fn stream_through(&mut self, count: u64, fault: impl FnOnce(&mut Lab) -> u64) -> Faulted {
        let sub_b = self.subscriber(true, "b.txt", u64::MAX);
        let sent = self.scratch.path("sent.txt");
        let publisher = self
            .a
            .helper("publish", &self.instance.clone(), &sent, count);
        self.b.proc(sub_b).wait_line("helper: first sample");
        let sent_before = fault(self);
        let (status, _, stderr) = self.a.proc(publisher).wait();
        assert!(status.success(), "{stderr}");
        self.b
            .proc(sub_b)
            .wait_line(&format!("helper: received {}", count - 1));
        self.b.proc(sub_b).signal(libc::SIGTERM);
        assert!(self.b.proc(sub_b).wait().0.success());
        let json_b = stop_link(&mut self.b, self.link_b);
        let json_a = stop_link(&mut self.a, self.link_a);

        let on_b = read_samples(&self.scratch.path("b.txt"));
        let sent = read_samples(&sent);
        for b in &on_b {
            assert_eq!(
                sent[b.0 as usize].1, b.1,
                "field {} not byte-identical",
                b.0
            );
        }
        let missing_on_b: u64 = on_b.windows(2).map(|w| w[1].0 - w[0].0 - 1).sum();
        assert_every_id_received_or_counted_lost(&json_b, count, missing_on_b);
        Faulted {
            json_b,
            sent_by_a: sent_before + json_a["out"]["fields"]["sent"].as_u64().unwrap(),
            received_on_b: on_b.len(),
            missing_on_b,
        }
    }
}

impl Faulted {
    fn print(&self, fault: &str, count: u64) {
        println!(
            "{fault}: a's links sent {} of {count}; b's link received {}, counted {} lost; \
             b's reader received {}, missed {}",
            self.sent_by_a,
            self.json_b["in"]["fields"]["received"],
            self.json_b["in"]["fields"]["lost"],
            self.received_on_b,
            self.missing_on_b
        );
    }
}

#[test]
fn a_link_restarted_mid_stream_resumes_with_the_gap_counted() {
    if !namespaces_available("restart") {
        return;
    }
    const COUNT: u64 = 1600;
    let mut lab = Lab::new("link_restart", 80);
    // a's link stops mid-stream (the publisher goes on) and starts again.
    let faulted = lab.stream_through(COUNT, |lab| {
        let first = stop_link(&mut lab.a, lab.link_a);
        let config_a = lab.config_a.clone();
        lab.link_a = lab.a.link(&lab.instance, &config_a, None);
        lab.a
            .proc(lab.link_a)
            .wait_line("fields out: a peer subscribes");
        first["out"]["fields"]["sent"].as_u64().unwrap()
    });
    faulted.print("restart", COUNT);
}

#[test]
fn the_network_down_for_five_seconds_loses_samples_counted_and_the_link_resumes() {
    if !namespaces_available("network_down") {
        return;
    }
    // 12 s of fields at 200 Hz; b's interface down for 5 s from the first field b gets.
    const COUNT: u64 = 2400;
    let mut lab = Lab::new("link_down", 81);
    let faulted = lab.stream_through(COUNT, |lab| {
        lab.b.sh("ip link set v81a down");
        std::thread::sleep(Duration::from_secs(5));
        lab.b.sh("ip link set v81a up");
        0
    });
    faulted.print("network down 5 s", COUNT);
}

/// What b's link last wrote of `service` coming in (its counts file), if anything yet.
fn counts_in(lab: &Lab, service: &str) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(&lab.counts_b).ok()?;
    let counts: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(counts["in"][service].clone())
}

/// Waits (bounded by the hang guard) until b's link's counts of `service` satisfy `done`.
fn wait_for_counts(lab: &Lab, service: &str, done: impl Fn(&serde_json::Value) -> bool) {
    let give_up = Instant::now() + HANG_GUARD;
    while !counts_in(lab, service).is_some_and(|c| done(&c)) {
        assert!(
            Instant::now() < give_up,
            "b's link: {service} never got there: {:?}",
            counts_in(lab, service)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// Issue 31, a lossless link for the small services: the rig's samples wait for the network
/// rather than being dropped. Host a's rig publishes at 500 Hz; b's interface goes down for
/// 2 s once b's link has its samples, and every sample the rig published still reaches b's
/// reader (`dicstream tap`), none counted lost by b's link, none dropped by a's. (With Zenoh's
/// default 1 ms wait for room before a drop, the samples that came while the network was down,
/// beyond what TCP held, were dropped and counted lost: 926 of 2500.)
#[test]
fn rig_samples_wait_through_a_short_outage_and_every_one_arrives() {
    if !namespaces_available("rig_outage") {
        return;
    }
    let mut lab = Lab::carrying("link_rig_outage", 83, "rig/state");
    let tap = lab.b.command(
        DICSTREAM,
        &["tap", "rig/state", "--json", "--instance", &lab.instance],
    );
    let tap = lab.b.spawn("tap", tap);
    lab.b.proc(tap).wait_line("tap: watching");
    let rig = lab.a.command(
        DICSTREAM,
        &[
            "rig",
            "--instance",
            &lab.instance,
            "--test",
            "uniaxial",
            "--specimen",
            "homogeneous",
            "--stretch",
            "1.2",
            "--rate",
            "0.01",
            "--publish-hz",
            "500",
            "--duration-s",
            "5",
        ],
    );
    let rig = lab.a.spawn("rig", rig);
    wait_for_counts(&lab, "rig/state", |c| c["received"].as_u64() > Some(0));
    lab.b.sh("ip link set v83a down");
    std::thread::sleep(Duration::from_secs(2));
    lab.b.sh("ip link set v83a up");
    let (status, _, stderr) = lab.a.proc(rig).wait();
    assert!(status.success(), "{stderr}");
    let published: u64 = stderr
        .split(" samples published")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count of the samples published: {stderr}"));
    wait_for_counts(&lab, "rig/state", |c| {
        c["last_id"].as_u64() == Some(published - 1)
    });
    lab.b.proc(tap).signal(libc::SIGTERM);
    let (status, tap_json, stderr) = lab.b.proc(tap).wait();
    assert!(status.success(), "{stderr}");
    let tap: serde_json::Value = serde_json::from_str(&tap_json).unwrap();
    let json_b = stop_link(&mut lab.b, lab.link_b);
    let json_a = stop_link(&mut lab.a, lab.link_a);
    let (out_a, in_b) = (&json_a["out"]["rig/state"], &json_b["in"]["rig/state"]);
    println!(
        "rig/state through a 2 s outage: the rig published {published}; a's link sent {}, \
         dropped {}; b's link received {}, counted {} lost; b's reader received {}, {} drops",
        out_a["sent"],
        out_a["overflowed"],
        in_b["received"],
        in_b["lost"],
        tap["received"],
        tap["drops"]
    );
    assert_eq!(in_b["lost"], 0, "{json_b}");
    assert_eq!(in_b["received"], published, "{json_b}");
    assert_eq!(out_a["overflowed"], 0, "{json_a}");
    assert_eq!(tap["first_id"], 0, "{tap}");
    assert_eq!(tap["last_id"], published - 1, "{tap}");
    assert_eq!(tap["received"], published, "{tap}");
}

/// The configuration of one host's part of a split strain-controlled run: the analytic sheet,
/// a small camera, one equibiaxial test under strain control to λ 1.12 at 0.01 /s (11 s of
/// ramp), and `[link]`, started by the run, with `endpoints` and `services`.
fn split_run_config(
    scratch: &Scratch,
    user: &str,
    processes: &str,
    endpoints: &str,
    services: &str,
) -> PathBuf {
    let link = link_config(scratch, user, endpoints, services);
    let link = std::fs::read_to_string(link).unwrap();
    scratch.write(
        &format!("{user}-run.toml"),
        &format!(
            "[run]\nprocesses = [{processes}]\ndashboard = \"off\"\nstatus_interval_s = 0.5\n\
             [camera]\nwidth_px = 256\nheight_px = 256\nfps = 10.0\n\
             [correlator]\nthreads = 1\n\
             [rig]\npublish_hz = 100.0\nlog_hz = 20.0\n\
             [[rig.tests]]\nkind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.12\n\
             rate_per_s = 0.01\nstale_s = 0.5\n\
             [specimen]\nmodel = \"homogeneous\"\n\
             {link}start_with_run = true\n"
        ),
    )
}

/// `dicstream run` of one host's part, results in `out`.
fn split_run(host: &mut Host, instance: &str, config: &Path, out: &Path) -> usize {
    let command = host.command(
        DICSTREAM,
        &[
            "run",
            "--quiet",
            "--instance",
            instance,
            "--config",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    host.spawn("run", command)
}

fn summary(out: &Path) -> serde_json::Value {
    let path = out.join("summary.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Waits (bounded by the hang guard) until `path` holds `text`.
fn wait_for_text(path: &Path, text: &str) {
    let give_up = Instant::now() + HANG_GUARD;
    while !std::fs::read_to_string(path).is_ok_and(|t| t.contains(text)) {
        assert!(
            Instant::now() < give_up,
            "no {text:?} in {}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// (control, X elongation, Y elongation) of every row of a whole `rig.csv`.
fn rig_rows(rig_csv: &Path) -> Vec<(String, f64, f64)> {
    let rows = common::bench_run::whole_rows(rig_csv).unwrap();
    let text = std::fs::read_to_string(rig_csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (mode, ex, ey) = (at("control"), at("X_elongation_mm"), at("Y_elongation_mm"));
    rows.iter()
        .map(|r| {
            (
                r[mode].clone(),
                r[ex].parse().unwrap(),
                r[ey].parse().unwrap(),
            )
        })
        .collect()
}

/// Issue 31, faults across the link: the rig on host a is strain-controlled from the fields
/// the camera, correlator and identifier compute on host b, each host's part started by its
/// own `dicstream run`, which starts the link. b's interface goes down for 5 s mid-ramp: the
/// rig holds within `stale_s` (its stale-field interlock), resumes once the link is back and
/// finishes its test; a's run says it held and resumed; each run says what its link lost (the
/// small services wait for the network, so that may be nothing), its verdict doubtful if
/// anything; every row written is whole.
#[test]
fn a_split_strain_controlled_run_holds_through_a_link_outage_and_resumes() {
    if !namespaces_available("split_outage") {
        return;
    }
    let instance = testkit::unique_instance("link_split");
    let scratch = Scratch::new(&instance);
    write_peers(&scratch);
    let (mut a, mut b) = (Host::new("a"), Host::new("b"));
    let (ip_a, _) = wire_up(&a, &b, 82);
    let service = |name: &str, direction: &str| {
        format!("{{ name = \"{name}\", direction = \"{direction}\" }}")
    };
    let config_a = split_run_config(
        &scratch,
        "host-a",
        "\"rig\"",
        &format!("listen = [\"tcp/{ip_a}:{PORT}\"]"),
        &[service("rig/state", "out"), service("fields", "in")].join(", "),
    );
    let config_b = split_run_config(
        &scratch,
        "host-b",
        "\"producer\", \"correlator\", \"identifier\"",
        &format!("connect = [\"tcp/{ip_a}:{PORT}\"]"),
        &[service("rig/state", "in"), service("fields", "out")].join(", "),
    );
    let (out_a, out_b) = (scratch.path("a"), scratch.path("b"));
    // The rig's host first: its strain control waits at rest for the first usable field.
    let run_a = split_run(&mut a, &instance, &config_a, &out_a);
    a.proc(run_a).wait_line("run: rig ready");
    let run_b = split_run(&mut b, &instance, &config_b, &out_b);
    // Strain control runs on a from b's fields: the link down once the ramp is under way.
    wait_for_text(&out_a.join("logs/rig.log"), "strain control started");
    common::bench_run::wait_rows(&out_a.join("frames.csv"), 0, 30);
    b.sh("ip link set v82a down");
    std::thread::sleep(Duration::from_secs(5));
    b.sh("ip link set v82a up");
    let (status_a, stdout_a, stderr_a) = a.proc(run_a).wait();
    let (status_b, stdout_b, stderr_b) = b.proc(run_b).wait();
    println!("host a's run: {status_a:?}\n{stdout_a}");
    println!("host b's run: {status_b:?}\n{stdout_b}");
    let (summary_a, summary_b) = (summary(&out_a), summary(&out_b));
    assert_eq!(summary_a["ending"], "completed", "{summary_a}\n{stderr_a}");
    assert_eq!(summary_b["ending"], "completed", "{summary_b}\n{stderr_b}");

    // The rig held on stale fields, then resumed, and its grips stayed still while held.
    let rig_log = std::fs::read_to_string(out_a.join("logs/rig.log")).unwrap();
    let held = rig_log
        .find("strain control HELD")
        .unwrap_or_else(|| panic!("no hold:\n{rig_log}"));
    let held_line = rig_log[held..].lines().next().unwrap();
    println!("{held_line}");
    assert!(held_line.contains("stale"), "{held_line}");
    assert!(
        rig_log[held..].contains("strain control resumed"),
        "no resumption after the hold:\n{rig_log}"
    );
    assert!(
        rig_log.contains("strain-controlled test finished"),
        "{rig_log}"
    );
    let rows = rig_rows(&out_a.join("rig.csv"));
    let mut k = 0;
    while k < rows.len() {
        let start = k;
        while k < rows.len() && rows[k].0 == "held" {
            k += 1;
        }
        if k > start + 1 {
            for axis in [1, 2] {
                let values = rows[start..k]
                    .iter()
                    .map(|r| if axis == 1 { r.1 } else { r.2 });
                let (lo, hi) =
                    values.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
                assert!(hi - lo < 0.1, "grips moved {} mm while held", hi - lo);
            }
        }
        k += 1;
    }
    for out in [&out_a, &out_b] {
        common::bench_run::whole_rows(&out.join("frames.csv")).unwrap();
    }
    // a's run says so: held and resumed.
    let holds = &summary_a["strain_target"]["holds"];
    assert!(holds["holds"].as_u64().unwrap() >= 1, "{summary_a}");
    assert!(holds["resumed"].as_u64().unwrap() >= 1, "{summary_a}");
    assert!(stdout_a.contains("HELD"), "{stdout_a}");
    // Each run says what its link lost, and its verdict counts it: the small services wait
    // for the network, so a 5 s outage may lose nothing (the fields and rig samples queued
    // came late: stale for the rig, which held on them).
    for (host, summary, stdout, status, stderr) in [
        ("a", &summary_a, &stdout_a, status_a, &stderr_a),
        ("b", &summary_b, &stdout_b, status_b, &stderr_b),
    ] {
        let lost = summary["link"]["lost"].as_u64().unwrap();
        match lost {
            0 => assert!(
                stdout.contains("run: link: nothing lost"),
                "{host}: {stdout}"
            ),
            _ => {
                assert!(stdout.contains("run: link: LOST"), "{host}: {stdout}");
                assert_eq!(status.code(), Some(2), "{host}: doubtful: {stderr}");
                assert!(
                    summary["failure"]
                        .as_str()
                        .is_some_and(|f| f.contains("the link to the other host lost")),
                    "{host}: {summary}"
                );
            }
        }
    }
    let (fields_in_a, rig_in_b) = (
        &summary_a["link"]["counts"]["in"]["fields"],
        &summary_b["link"]["counts"]["in"]["rig/state"],
    );
    assert!(rig_in_b["received"].as_u64().unwrap() > 0, "{summary_b}");
    println!(
        "link down 5 s: strain control held {} time(s) for {:.1} s; a's link: fields {} \
         received, {} lost; b's link: rig/state {} received, {} lost",
        holds["holds"],
        holds["held_s"].as_f64().unwrap(),
        fields_in_a["received"],
        fields_in_a["lost"],
        rig_in_b["received"],
        rig_in_b["lost"]
    );
}

#[test]
fn bad_configurations_are_refused_before_anything_starts() {
    // Refused before any session opens: nothing here reaches a network.
    let scratch = Scratch::new(&testkit::unique_instance("link_refusals"));
    let refused = |name: &str, text: &str| {
        let config = scratch.write(name, text);
        let out = Command::new(DICSTREAM)
            .args(["link", "--instance", "refusals", "--config"])
            .arg(&config)
            .output()
            .unwrap();
        assert!(out.stdout.is_empty(), "{out:?}");
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let good = "[link]\nlisten = [\"tcp/10.0.0.1:7447\"]\nuser = \"a\"\n\
                password_file = \"/nonexistent/pw\"\npeers_file = \"/nonexistent/peers\"\n\
                services = [{ name = \"fields\", direction = \"out\" }]\n";
    let (code, stderr) = refused("any.toml", &good.replace("10.0.0.1", "0.0.0.0"));
    assert_eq!(code, Some(78), "{stderr}");
    assert!(
        stderr.contains("[link] listen: tcp/0.0.0.0:7447 listens on every interface"),
        "{stderr}"
    );
    let (code, stderr) = refused("none.toml", "[run]\nvtk = false\n");
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("no [link] section"), "{stderr}");
    let (code, stderr) = refused("pw.toml", good);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("[link] password_file /nonexistent/pw"),
        "{stderr}"
    );
}

/// The helpers, when this binary is run again inside a host (`ROLE` set); otherwise nothing.
#[test]
fn helper_role() {
    let Ok(role) = std::env::var(ROLE) else {
        return;
    };
    // SIGTERM stops a subscriber helper, which then writes what it received.
    wire::signals::install().unwrap();
    let var = |name: &str| std::env::var(name).unwrap();
    let instance = wire::Instance::new(&var("HELPER_INSTANCE")).unwrap();
    let out = PathBuf::from(var("HELPER_OUT"));
    let count: u64 = var("HELPER_COUNT").parse().unwrap();
    match role.as_str() {
        "publish" => publish(&instance, &out, count),
        "subscribe" => subscribe(&instance, &out, count),
        _ => panic!("unknown role {role}"),
    }
}

/// The checksum of a field's bytes, header and nodes.
fn field_checksum(header: &FieldHeader, nodes: &[FieldNode]) -> u64 {
    let mut bytes = value_bytes(header).to_vec();
    bytes.extend_from_slice(slice_bytes(nodes));
    wire::frame::byte_checksum(&bytes)
}

/// Publishes `count` fields at 200 Hz, ids 0.., writing "id checksum 0" per field.
fn publish(instance: &wire::Instance, out: &Path, count: u64) {
    let (node, _) = instance.create_node("helper-publisher").unwrap();
    let nodes = (MESH_SIDE * MESH_SIDE) as usize;
    let publisher =
        SlicePublisher::<FieldNode, FieldHeader>::create(&node, &services::FIELDS, nodes).unwrap();
    let mut lines = String::new();
    let started = Instant::now();
    for id in 0..count {
        let due = started + Duration::from_millis(5 * id);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        let mut checksum = 0;
        publisher
            .publish(nodes, |header, payload| {
                header.frame_id = id;
                header.mesh_cols = MESH_SIDE;
                header.mesh_rows = MESH_SIDE;
                for (k, node) in payload.iter_mut().enumerate() {
                    *node = FieldNode {
                        x_px: (k % 16) as f32 * 8.0,
                        y_px: (k / 16) as f32 * 8.0,
                        u_px: id as f32 * 1e-3 + k as f32 * 1e-5,
                        v_px: -(id as f32) * 2e-3,
                        ..FieldNode::default()
                    };
                }
                header.t_published_ns = wire::monotonic_ns();
                checksum = field_checksum(header, payload);
                Ok::<bool, ()>(true)
            })
            .unwrap()
            .unwrap();
        lines.push_str(&format!("{id} {checksum} 0\n"));
    }
    std::fs::write(out, lines).unwrap();
    eprintln!("helper: published {count}");
}

/// Receives fields until id `count - 1` (or a signal), writing "id checksum latency_ns".
fn subscribe(instance: &wire::Instance, out: &Path, count: u64) {
    let (node, _) = instance.create_node("helper-subscriber").unwrap();
    let subscriber =
        SliceSubscriber::<FieldNode, FieldHeader>::create(&node, &services::FIELDS).unwrap();
    let waitset = wire::signals::waitset().unwrap();
    let _guard = waitset.attach_notification(subscriber.listener()).unwrap();
    eprintln!("helper: subscribed");
    let mut lines = String::new();
    let give_up = Instant::now() + HANG_GUARD;
    let mut received = 0u64;
    'wait: while wire::signals::requested().is_none() && Instant::now() < give_up {
        subscriber.clear_events();
        while let Some(sample) = subscriber.receive().unwrap() {
            let latency_ns = wire::monotonic_ns() - sample.user_header().t_published_ns;
            let header = *sample.user_header();
            let checksum = field_checksum(&header, sample.payload());
            lines.push_str(&format!("{} {checksum} {latency_ns}\n", header.frame_id));
            if received == 0 {
                eprintln!("helper: first sample {}", header.frame_id);
            }
            received += 1;
            if header.frame_id % 100 == 99 || header.frame_id + 1 == count {
                eprintln!("helper: received {}", header.frame_id);
            }
            if header.frame_id + 1 >= count {
                break 'wait;
            }
        }
        waitset
            .wait_and_process_once_with_timeout(
                |_| iceoryx2::prelude::CallbackProgression::Continue,
                Duration::from_millis(100),
            )
            .unwrap();
    }
    std::fs::write(out, lines).unwrap();
}
