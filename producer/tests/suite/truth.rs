//! Truth of every scenario: φ⁻¹∘φ = identity, F against central finite differences, the
//! ramp (identity at frame 0), and clear errors for unknown names and parameters.

use producer::{Motion, Scenario, SCENARIO_NAMES};

const W: u32 = 512;
const H: u32 = 384;

fn points() -> impl Iterator<Item = [f64; 2]> {
    (0..=8).flat_map(|i| (0..=8).map(move |j| [f64::from(i) * 63.9, f64::from(j) * 47.9]))
}

fn check_motion(name: &str, m: &Motion) {
    for p in points() {
        let x = m.forward(p);
        let back = m.inverse(x);
        let err = (back[0] - p[0]).hypot(back[1] - p[1]);
        assert!(
            err < 1e-9,
            "{name}: inverse(forward({p:?})) off by {err:e} px"
        );
        let h = 1e-4;
        let f = m.gradient(p);
        for j in 0..2 {
            let mut a = p;
            let mut b = p;
            a[j] -= h;
            b[j] += h;
            let (fa, fb) = (m.forward(a), m.forward(b));
            for i in 0..2 {
                let fd = (fb[i] - fa[i]) / (2.0 * h);
                assert!(
                    (fd - f[i][j]).abs() < 1e-7,
                    "{name}: F[{i}][{j}] = {} but finite difference {fd} at {p:?}",
                    f[i][j]
                );
            }
        }
        let u = m.displacement(p);
        assert_eq!(u, [x[0] - p[0], x[1] - p[1]]);
    }
}

#[test]
fn every_scenario_is_consistent() {
    for name in SCENARIO_NAMES {
        let scenario = Scenario::parse(name, W, H).unwrap();
        assert_eq!(scenario.kind.name(), name);
        assert_eq!(scenario.motion_at(0, 10), {
            // Frame 0 is the identity (affine about the centre, or a zero-amplitude field).
            scenario.motion_at_fraction(0.0)
        });
        let m0 = scenario.motion_at(0, 10);
        for p in points() {
            let u = m0.displacement(p);
            assert!(
                u[0].abs() < 1e-12 && u[1].abs() < 1e-12,
                "{name}: frame 0 moves"
            );
        }
        for k in [3, 9] {
            let m = scenario.motion_at(k, 10);
            check_motion(name, &m);
            let truth = scenario.truth_of(&m);
            assert_eq!(truth.scenario_id, scenario.kind.id());
            assert_eq!(truth.homogeneous, m.is_homogeneous());
            let c = truth.centre_px;
            let x = m.forward(c);
            assert!((x[0] - c[0] - truth.translation_px[0]).abs() < 1e-12);
            assert!((x[1] - c[1] - truth.translation_px[1]).abs() < 1e-12);
        }
    }
}

#[test]
fn final_states_match_the_paper() {
    let rot = Scenario::parse("rotation:angle_deg=5", W, H).unwrap();
    let Motion::Affine(a) = rot.motion_at(4, 5) else {
        panic!("rotation is affine")
    };
    assert!((a.f[0][0] - 5f64.to_radians().cos()).abs() < 1e-15);
    let uni = Scenario::parse("uniaxial:lambda=1.2", W, H).unwrap();
    let f = uni.motion_at(1, 2).gradient([0.0, 0.0]);
    assert!((f[0][0] - 1.2).abs() < 1e-15 && (f[1][1] - 1.2f64.powf(-0.5)).abs() < 1e-15);
    assert!(
        (f[0][0] * f[1][1] - 1.2f64.sqrt()).abs() < 1e-12,
        "sheet: λ1 λ2 λ3 = 1"
    );
    let equi = Scenario::parse("equibiaxial", W, H).unwrap();
    let f = equi.motion_at(1, 2).gradient([0.0, 0.0]);
    assert_eq!(f, [[1.07, 0.0], [0.0, 1.07]]);
    let chirp = Scenario::parse("chirp:amplitude_px=0.1,periods=6", W, H).unwrap();
    let m = chirp.motion_at(1, 2);
    let mut max_u: f64 = 0.0;
    for i in 0..W {
        let u = m.displacement([f64::from(i), 7.0]);
        assert_eq!(u[1], 0.0, "chirp has v = 0");
        max_u = max_u.max(u[0].abs());
    }
    assert!((max_u - 0.1).abs() < 1e-3, "chirp amplitude {max_u}");
}

#[test]
fn unknown_scenario_lists_the_known_ones() {
    let error = Scenario::parse("twist", W, H).unwrap_err().to_string();
    assert!(error.contains("twist"), "{error}");
    for name in SCENARIO_NAMES {
        assert!(error.contains(name), "{error}");
    }
}

#[test]
fn bad_parameters_are_clear_errors() {
    let error = Scenario::parse("rotation:angel_deg=5", W, H)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("angel_deg") && error.contains("angle_deg"),
        "{error}"
    );
    let error = Scenario::parse("uniaxial:lambda=abc", W, H)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("lambda") && error.contains("number"),
        "{error}"
    );
    let error = Scenario::parse("chirp:amplitude_px=50,periods=50", W, H)
        .unwrap_err()
        .to_string();
    assert!(error.contains("invertible"), "{error}");
    assert!(Scenario::parse("uniaxial:lambda=-1", W, H).is_err());
}
