//! The live process over iceoryx2: a simulated rig and correlator publish a Smactane uniaxial
//! then equibiaxial path; the process pairs, refits, publishes reports and writes its JSON.

use identifier::law::InvariantLaw;
use identifier::online::OnlineConfig;
use identifier::process::{run, ProcessConfig};
use std::time::{Duration, Instant};
use wire::identification::IdentifierRoutes;
use wire::pubsub::{SlicePublisher, ValuePublisher, ValueSubscriber};
use wire::{
    services, FieldHeader, FieldNode, GaugeStrain, IdentificationReport, Instance, RigState,
    StrainMeasure,
};

const STEPS: u64 = 30;

#[test]
fn live_process_identifies_smactane() {
    // Its files are removed when it is dropped, also when the test fails.
    let test_instance = testkit::TestInstance::new("identifier_process");
    let name = test_instance.name().to_string();
    let instance = Instance::new(&name).unwrap();
    let output = std::env::temp_dir().join(format!("{name}_identification.json"));
    let journal = std::env::temp_dir().join(format!("{name}_points.csv"));
    let _ = std::fs::remove_file(&journal);
    let config = ProcessConfig {
        instance: name.clone(),
        output_json: output.clone(),
        journal: Some(journal.clone()),
        max_fields: Some(2 * STEPS),
        idle_timeout: Some(Duration::from_secs(20)),
        online: OnlineConfig::default(),
        routes: IdentifierRoutes::Gauge,
        field: None,
        states_csv: None,
    };
    let worker = std::thread::spawn(move || run(config));
    {
        let (node, _) = instance.create_node("testbench").unwrap();
        let rig: ValuePublisher<RigState> =
            ValuePublisher::create(&node, &services::RIG_STATE).unwrap();
        let fields: SlicePublisher<FieldNode, FieldHeader> =
            SlicePublisher::create(&node, &services::FIELDS, 1).unwrap();
        let reports: ValueSubscriber<IdentificationReport> =
            ValueSubscriber::create(&node, &services::IDENTIFICATION).unwrap();
        // Wait (bounded) until the process subscribes.
        let start = Instant::now();
        while rig.publish(RigState::default()).unwrap() == 0 {
            assert!(
                start.elapsed() < testkit::HANG_GUARD,
                "process never subscribed"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        let law = InvariantLaw::smactane();
        let mut sample_id = 1;
        let mut last_report = None;
        for (case_stretch, equibiaxial) in [(3.0, false), (2.0, true)] {
            for k in 1..=STEPS {
                let stretch = 1.0 + (case_stretch - 1.0) * k as f64 / STEPS as f64;
                let (l1, l2) = if equibiaxial {
                    (stretch, stretch)
                } else {
                    (stretch, 1.0 / stretch.sqrt())
                };
                let s = law.in_plane_stress(l1, l2);
                let (sx, sy) = (20.0 * l2 * 2.0 * s.stretch3, 20.0 * l1 * 2.0 * s.stretch3);
                let mut state = RigState {
                    sample_id,
                    specimen_section_x_mm2: sx,
                    specimen_section_y_mm2: sy,
                    ..RigState::default()
                };
                let (fx_kn, fy_kn) = (
                    s.cauchy_stress_mpa[0] * sx / 1e3,
                    s.cauchy_stress_mpa[1] * sy / 1e3,
                );
                for (i, f) in [fx_kn, fx_kn, fy_kn, fy_kn].into_iter().enumerate() {
                    state.actuators[i].force_kn = f;
                }
                rig.publish(state).unwrap();
                fields
                    .publish(1, |header, nodes| {
                        nodes[0] = FieldNode::default();
                        header.frame_id = sample_id;
                        header.rig_sample_id = sample_id;
                        header.mesh_cols = 1;
                        header.mesh_rows = 1;
                        header.gauge[StrainMeasure::Log as usize] = GaugeStrain {
                            exx: l1.ln(),
                            eyy: l2.ln(),
                            exy: 0.0,
                        };
                        Ok::<bool, ()>(true)
                    })
                    .unwrap()
                    .unwrap();
                // Pace: once refits start, wait for the report of this point (bounded).
                let points_sent = sample_id as u32;
                let deadline = Instant::now() + Duration::from_secs(10);
                loop {
                    while let Some(r) = reports.receive().unwrap() {
                        last_report = Some(r);
                    }
                    let seen = last_report
                        .map_or(0, |r: IdentificationReport| r.points.iter().sum::<u32>());
                    if points_sent < 8 || seen >= points_sent || Instant::now() > deadline {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(2));
                }
                if points_sent < 8 {
                    std::thread::sleep(Duration::from_millis(5));
                }
                sample_id += 1;
            }
        }
        let report = last_report.expect("reports were published");
        assert_eq!(report.points, [STEPS as u32, STEPS as u32, 0]);
        assert_eq!((report.a_count, report.b_count), (3, 3));
        let truth = [-1.27, -2.52e-2, 1.40e-3];
        for (a, t) in report.a.iter().zip(truth) {
            assert!((a - t).abs() < 1e-3, "a = {:?}", &report.a[..3]);
        }
        eprintln!(
            "last report: a = {:?}, b = {:?}, ranked {}",
            &report.a[..3],
            &report.b[..3],
            report.ranked_count
        );
    }
    let summary = worker.join().unwrap().unwrap();
    eprintln!("summary: {summary:?}");
    assert_eq!(summary.points, [STEPS as usize, STEPS as usize, 0]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&output).unwrap()).unwrap();
    assert_eq!(json["points"]["uniaxial"], STEPS);
    assert!(json["fits"].as_array().is_some_and(|f| !f.is_empty()));
    std::fs::remove_file(&output).unwrap();

    // A restarted identifier (same journal) rebuilds the whole path before any new data.
    let again = ProcessConfig {
        instance: name.clone(),
        output_json: output.clone(),
        journal: Some(journal.clone()),
        max_fields: None,
        idle_timeout: Some(Duration::from_millis(300)),
        online: OnlineConfig::default(),
        routes: IdentifierRoutes::Gauge,
        field: None,
        states_csv: None,
    };
    let summary = run(again).unwrap();
    assert_eq!(summary.points, [STEPS as usize, STEPS as usize, 0]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&output).unwrap()).unwrap();
    assert_eq!(json["points"]["equibiaxial"], STEPS);
    assert!(json["fits"].as_array().is_some_and(|f| !f.is_empty()));
    std::fs::remove_file(&output).unwrap();
    std::fs::remove_file(&journal).unwrap();
    instance.remove_leftover_files();
    assert!(instance.leftover_files().is_empty());
}
