//! The strain loop closed over iceoryx2 (issue 16): the rig process runs a strain-controlled
//! pure-shear test; this test plays the correlator, publishing on `fields` the gauge zone's log
//! strains of the newest rig sample at 20 frames/s, naming that sample as a frame does. Fields
//! pause mid-ramp: the rig holds (rig.csv `held`, the grips still) and resumes when they come
//! back; the test ends unloaded. Runs under its own instance prefix and removes its files.

use crate::rig_options::rig_options;

use rig::process::{run, ProcessOptions, StrainOptions};
use rig::strain::StrainTest;
use std::time::{Duration, Instant};
use wire::pubsub::{SlicePublisher, ValueSubscriber};
use wire::{FieldHeader, FieldNode, RigState, StrainMeasure};

fn column(header: &str, name: &str) -> usize {
    header
        .split(',')
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn a_strain_controlled_rig_follows_fields_holds_while_they_stop_and_resumes() {
    let test_instance = testkit::TestInstance::new("rig_strain_process");
    let name = test_instance.name().to_string();
    let dir = std::env::temp_dir().join(format!("{name}_out"));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("rig.csv");
    let test = StrainTest::new(rig::strain::StrainKind::PureShear, None, 1.15, 0.05)
        .unwrap()
        .with_interlocks(0.3, 16, rig::strain::control::OnRestore::Resume)
        .unwrap();
    let options = ProcessOptions {
        log_path: Some(log.clone()),
        log_hz: 50.0,
        duration_s: Some(60.0),
        exit_when_done: true,
        state_dir: Some(dir.clone()),
        strain: Some(StrainOptions {
            test,
            specimen: rig::builtin::BuiltinTest::Equibiaxial.specimen(&Default::default()),
        }),
        ..rig_options(&name)
    };
    let rig_options = options.clone();
    let rig_thread = std::thread::spawn(move || run(rig_options));

    // The correlator: the newest rig sample's gauge log strains, 20 fields/s, none from
    // t = 2.0 s to 2.8 s of rig time (mid-ramp).
    let instance = wire::Instance::new(&name).unwrap();
    let (node, _) = instance.create_node("strain_test_camera").unwrap();
    let states = ValueSubscriber::<RigState>::create(&node, &wire::services::RIG_STATE).unwrap();
    let fields =
        SlicePublisher::<FieldNode, FieldHeader>::create(&node, &wire::services::FIELDS, 1)
            .unwrap();
    let deadline = Instant::now() + testkit::HANG_GUARD;
    let mut newest: Option<RigState> = None;
    let mut published = 0u32;
    while !rig_thread.is_finished() {
        assert!(Instant::now() < deadline, "the strain test did not end");
        while let Some(s) = states.receive().unwrap() {
            newest = Some(s);
        }
        if let Some(s) = newest.filter(|s| !(2.0..2.8).contains(&s.t_sim_s)) {
            fields
                .publish(0, |h: &mut FieldHeader, _| {
                    h.rig_sample_id = s.sample_id;
                    h.t_capture_ns = s.t_published_ns;
                    h.valid_nodes = 400;
                    let g = &mut h.gauge[StrainMeasure::Log as usize];
                    g.exx = s.specimen_stretch_x.ln();
                    g.eyy = s.specimen_stretch_y.ln();
                    Ok::<bool, ()>(true)
                })
                .unwrap()
                .unwrap();
            published += 1;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let summary = rig_thread.join().unwrap().unwrap();
    println!("{summary:?}, {published} fields published");

    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let (c_mode, c_tx, c_ty) = (
        column(header, "control"),
        column(header, "target_log_exx"),
        column(header, "target_log_eyy"),
    );
    let (c_t, c_ex, c_sx, c_sy) = (
        column(header, "t_s"),
        column(header, "X_elongation_mm"),
        column(header, "stretch_x"),
        column(header, "stretch_y"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Modes in order: held (waiting for the first field), strain, held (fields stopped), strain,
    // displacement (unloading).
    let mut modes: Vec<&str> = Vec::new();
    for r in &rows {
        if modes.last() != Some(&r[c_mode]) {
            modes.push(r[c_mode]);
        }
    }
    if modes.first() == Some(&"held") {
        modes.remove(0);
    }
    assert_eq!(
        modes,
        ["strain", "held", "strain", "displacement"],
        "{modes:?}"
    );
    let f = |r: &Vec<&str>, c: usize| r[c].parse::<f64>().unwrap();
    // While held mid-ramp the grips stay where they were.
    let held: Vec<&Vec<&str>> = rows
        .iter()
        .filter(|r| r[c_mode] == "held" && f(r, c_t) > 1.5)
        .collect();
    assert!(!held.is_empty());
    let span = held.iter().map(|r| f(r, c_ex)).fold(f64::NAN, f64::max)
        - held.iter().map(|r| f(r, c_ex)).fold(f64::NAN, f64::min);
    assert!(span < 0.05, "the grips moved {span} mm while held");
    // The stale limit (0.3 s) after the fields stopped at 2.0 s, the hold starts.
    let held_from = f(held[0], c_t);
    assert!((2.0..2.0 + 0.3 + 0.1).contains(&held_from), "{held_from}");
    // Under strain control: targets are logged, the gauge zone stays in pure shear.
    let mut worst_y = 0.0f64;
    let mut reached = 0.0f64;
    for r in rows.iter().filter(|r| r[c_mode] == "strain") {
        // The path starts from the measured state (within noise of 0): ln λy's target stays there.
        assert!(f(r, c_tx).is_finite() && f(r, c_ty).abs() < 1e-3, "{r:?}");
        worst_y = worst_y.max(f(r, c_sy).ln().abs());
        reached = reached.max(f(r, c_sx));
    }
    println!("pure shear over IPC: worst |ln λy| {worst_y:.5}, λx reached {reached:.4}");
    assert!(worst_y < 0.005, "|ln λy| {worst_y}");
    assert!((reached - 1.15).abs() < 0.01, "λx {reached}");
    // Unloaded at the end, under displacement control with no target.
    let last = rows.last().unwrap();
    assert!(f(last, c_ex).abs() < 0.1);
    assert_eq!((last[c_tx], last[c_ty]), ("", ""));

    // A restart with the same state folder refuses (exit 75): fields cannot be replayed.
    let error = run(options).unwrap_err();
    assert_eq!(wire::exit::code_of(&error), Some(wire::exit::CANNOT_RESUME));
    assert!(error.to_string().contains("not replayed"), "{error}");

    drop(fields);
    drop(states);
    drop(node);
    instance.remove_leftover_files();
    let _ = std::fs::remove_dir_all(&dir);
}
