//! The cruciform: its mesh (area, grips, slits, refusals) and the mesh convergence of the arm
//! force at a grip stretch of 2.

use crate::common;

use common::Solved;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{GeometryError, NewtonSettings};
use std::time::Instant;

#[test]
fn cruciform_mesh_has_the_area_of_the_drawing_and_four_grips() {
    for geometry in [
        CruciformGeometry::default(),
        CruciformGeometry {
            fillet_radius_mm: 0.0,
            ..CruciformGeometry::default()
        },
        CruciformGeometry {
            slits_per_arm: 3,
            slit_length_mm: 40.0,
            ..CruciformGeometry::default()
        },
    ] {
        let specimen = geometry.mesh().unwrap();
        let area = specimen.mesh.area_mm2().unwrap();
        let exact = geometry.area_mm2();
        assert!((area - exact).abs() < 1e-4 * exact, "{area} vs {exact} mm²");
        assert_eq!(specimen.grips.len(), 4);
        let across = specimen.grip("x+").unwrap().nodes.len();
        for grip in &specimen.grips {
            assert_eq!(grip.nodes.len(), across, "{}", grip.name);
            for &n in &grip.nodes {
                let p = specimen.mesh.nodes_mm[n];
                let along = p[0] * grip.axis[0] + p[1] * grip.axis[1];
                assert!((along - 130.0).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn slits_cut_the_arms_into_fingers() {
    let plain = CruciformGeometry::default().mesh().unwrap();
    let geometry = CruciformGeometry {
        slits_per_arm: 1,
        slit_length_mm: 40.0,
        ..CruciformGeometry::default()
    };
    let slit = geometry.mesh().unwrap();
    assert_eq!(slit.mesh.elements.len(), plain.mesh.elements.len());
    // Each arm's slit doubles its nodes from the grip to (not including) the slit's tip:
    // 40 mm of 10 mm elements, 8 half-cells, 4 slits.
    assert_eq!(slit.mesh.nodes_mm.len(), plain.mesh.nodes_mm.len() + 4 * 8);
    assert_eq!(
        slit.grip("x+").unwrap().nodes.len(),
        plain.grip("x+").unwrap().nodes.len() + 1
    );
}

#[test]
fn geometries_that_cannot_be_meshed_are_refused_with_the_value() {
    let base = CruciformGeometry::default();
    let cases = [
        (
            CruciformGeometry {
                fillet_radius_mm: 120.0,
                ..base
            },
            GeometryError::FilletTooLarge {
                radius_mm: 120.0,
                limit_name: "arm width",
                limit_mm: 100.0,
            },
        ),
        (
            CruciformGeometry {
                arm_length_mm: 15.0,
                ..base
            },
            GeometryError::FilletTooLarge {
                radius_mm: 20.0,
                limit_name: "arm length",
                limit_mm: 15.0,
            },
        ),
        (
            CruciformGeometry {
                arm_width_mm: -3.0,
                ..base
            },
            GeometryError::NotPositive {
                name: "arm width",
                value_mm: -3.0,
            },
        ),
        (
            CruciformGeometry {
                element_size_mm: 0.0,
                ..base
            },
            GeometryError::NotPositive {
                name: "element size",
                value_mm: 0.0,
            },
        ),
    ];
    for (geometry, expected) in cases {
        assert_eq!(geometry.mesh().unwrap_err(), expected);
    }
    let too_long = CruciformGeometry {
        slits_per_arm: 2,
        slit_length_mm: 70.0,
        ..base
    };
    assert!(matches!(
        too_long.mesh(),
        Err(GeometryError::Slit { count: 2, .. })
    ));
    let too_fine = CruciformGeometry {
        element_size_mm: 1e-3,
        ..base
    };
    assert!(matches!(
        too_fine.mesh(),
        Err(GeometryError::TooManyElements { .. })
    ));
}

/// Arm force (N) at a grip stretch of 2 (each grip pulled by half the grip-to-grip distance),
/// with the free DOFs and the time to mesh, solve and evaluate the fields (ms).
fn arm_force_at_grip_stretch_2(element_size_mm: f64) -> (f64, usize, f64) {
    let geometry = CruciformGeometry {
        element_size_mm,
        ..CruciformGeometry::default()
    };
    let pull_mm = 0.5 * geometry.arm_width_mm + geometry.arm_length_mm;
    let started = Instant::now();
    let solved = Solved::new(
        geometry.mesh().unwrap(),
        |s| s.pull_all(pull_mm),
        NewtonSettings::default(),
    );
    let ms = started.elapsed().as_secs_f64() * 1e3;
    let equilibrium = &solved.equilibrium;
    let last = equilibrium.steps.last().unwrap();
    println!(
        "h = {element_size_mm} mm: {} steps, last residuals {:?}, states {:?}",
        equilibrium.steps.len(),
        last.residuals_n,
        last.states
    );
    (solved.grip_force_n("x+")[0], equilibrium.free_dofs, ms)
}

#[test]
fn arm_force_converges_with_the_mesh() {
    println!("| element mm | free DOFs | arm force N | change | solve ms |");
    let mut previous: Option<f64> = None;
    let mut changes = Vec::new();
    for size in [20.0, 10.0, 5.0] {
        let (force, dofs, ms) = arm_force_at_grip_stretch_2(size);
        let change = previous.map(|p| (force - p) / p);
        println!(
            "| {size} | {dofs} | {force:.4} | {} | {ms:.0} |",
            change.map_or("".into(), |c| format!("{:+.3} %", 100.0 * c))
        );
        changes.extend(change);
        previous = Some(force);
    }
    // Default mesh (10 mm) to twice finer.
    assert!(changes[1].abs() < 5e-3, "{changes:?}");
}

#[test]
fn misalignment_is_a_boundary_condition() {
    let geometry = CruciformGeometry {
        element_size_mm: 20.0,
        ..CruciformGeometry::default()
    };
    let pull_mm = 0.25 * (0.5 * geometry.arm_width_mm + geometry.arm_length_mm);
    let aligned = Solved::new(
        geometry.mesh().unwrap(),
        |s| s.pull_all(pull_mm),
        NewtonSettings::default(),
    );
    // The sheet turned by 3° in the x+ grip, and clamped off-centre along x: x- pulls 1.5 times
    // what x+ pulls.
    let misaligned = Solved::new(
        geometry.mesh().unwrap(),
        |s| {
            s.grips
                .iter()
                .map(|g| match g.name {
                    "x+" => g.clamp(pull_mm, 3f64.to_radians()),
                    "x-" => g.clamp(1.5 * pull_mm, 0.0),
                    _ => g.clamp(pull_mm, 0.0),
                })
                .collect()
        },
        NewtonSettings::default(),
    );
    for solved in [&aligned, &misaligned] {
        let total = ["x+", "y+", "x-", "y-"]
            .map(|g| solved.grip_force_n(g))
            .iter()
            .fold([0.0; 2], |acc, f| [acc[0] + f[0], acc[1] + f[1]]);
        let scale = solved.grip_force_n("x+")[0];
        assert!(
            total[0].abs() < 1e-8 * scale && total[1].abs() < 1e-8 * scale,
            "{total:?}"
        );
    }
    let (straight, turned) = (aligned.grip_force_n("x+"), misaligned.grip_force_n("x+"));
    println!("x+ grip force aligned {straight:?} N, misaligned {turned:?} N");
    // Aligned, only the mesh's own asymmetry (alternating diagonals) pulls sideways.
    assert!(straight[1].abs() < 2e-4 * straight[0], "{straight:?}");
    assert!(turned[1].abs() > 20.0 * straight[1].abs(), "{turned:?}");
}

#[test]
fn a_slit_cruciform_is_solved_with_its_fingers_free() {
    let geometry = CruciformGeometry {
        element_size_mm: 10.0,
        slits_per_arm: 3,
        slit_length_mm: 40.0,
        ..CruciformGeometry::default()
    };
    let plain = CruciformGeometry {
        slits_per_arm: 0,
        ..geometry
    };
    let pull_mm = 0.5 * (0.5 * geometry.arm_width_mm + geometry.arm_length_mm);
    let force = |g: CruciformGeometry| {
        let solved = Solved::new(
            g.mesh().unwrap(),
            |s| s.pull_all(pull_mm),
            NewtonSettings::default(),
        );
        let last = solved.equilibrium.steps.last().unwrap();
        println!(
            "{} slits: residuals {:?}, states {:?}",
            g.slits_per_arm, last.residuals_n, last.states
        );
        solved.grip_force_n("x+")[0]
    };
    let (slit, whole) = (force(geometry), force(plain));
    println!("arm force at grip stretch 1.5: slit {slit:.3} N, whole {whole:.3} N");
    // The fingers do not pull each other sideways: the slit arm is softer.
    assert!(slit < whole && slit > 0.5 * whole, "{slit} vs {whole}");
}

/// A camera's view of the cruciform: the arms cut at the view's edges (each at its own
/// reach), the area of the drawing less the arms' parts outside, grips on the cut edges; a
/// view short of an arm's straight part, or a slit cruciform, refused.
#[test]
fn a_cruciform_clipped_to_a_view_ends_at_the_views_edges() {
    let geometry = CruciformGeometry::default();
    let (x_mm, y_mm) = ([-78.0, 76.0], [-74.5, 79.0]);
    let clipped = geometry.clipped(x_mm, y_mm).unwrap();
    let outside_mm: f64 = [130.0 - 78.0, 130.0 - 76.0, 130.0 - 74.5, 130.0 - 79.0]
        .iter()
        .map(|length| 100.0 * length)
        .sum();
    let exact = geometry.area_mm2() - outside_mm;
    let area = clipped.mesh.area_mm2().unwrap();
    assert!((area - exact).abs() < 1e-4 * exact, "{area} vs {exact} mm²");
    for (name, reach_mm) in [("x+", 76.0), ("x-", 78.0), ("y+", 79.0), ("y-", 74.5)] {
        let grip = clipped.grip(name).unwrap();
        assert!(grip.nodes.len() >= 11, "{name}: {}", grip.nodes.len());
        for &n in &grip.nodes {
            let p = clipped.mesh.nodes_mm[n];
            assert!((p[0] * grip.axis[0] + p[1] * grip.axis[1] - reach_mm).abs() < 1e-9);
        }
    }
    // Beyond the grips: the whole specimen.
    let whole = geometry.clipped([-200.0, 200.0], [-200.0, 200.0]).unwrap();
    assert_eq!(whole, geometry.mesh().unwrap());
    // The view stops in the x− fillet.
    let error = geometry.clipped([-65.0, 78.0], y_mm).unwrap_err();
    assert_eq!(
        error,
        GeometryError::ArmNotCut {
            arm: "x-",
            reach_mm: 65.0,
            straight_mm: 70.0
        }
    );
    assert!(
        error.to_string().contains("arm x-: the view reaches 65 mm"),
        "{error}"
    );
    let slit = CruciformGeometry {
        slits_per_arm: 1,
        slit_length_mm: 40.0,
        ..CruciformGeometry::default()
    };
    assert!(matches!(
        slit.clipped(x_mm, y_mm),
        Err(GeometryError::Slit { .. })
    ));
}
