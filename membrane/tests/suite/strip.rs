//! The specimens between clamps: the uniaxial strip far from its clamps, the plane-strain
//! strip (λ2 = 1 within 2e-3 farther than 4 lengths from its free edges), a sheared sheet that
//! wrinkles, and Newton's quadratic convergence on one of them.

use crate::common;

use common::Solved;
use material::InvariantLaw;
use membrane::specimens::strip::StripGeometry;
use membrane::{MembraneState, NewtonSettings, Specimen, Wrinkling};

#[test]
fn strip_far_from_the_clamps_is_in_uniaxial_tension() {
    let law = InvariantLaw::smactane();
    let geometry = StripGeometry::uniaxial();
    let pull_mm = 0.5 * geometry.length_mm; // grip stretch 2
    let solved = Solved::new(
        geometry.mesh().unwrap(),
        |s| s.pull_all(pull_mm),
        NewtonSettings::default(),
    );
    let fields = &solved.fields;
    let mut checked = 0;
    for field in fields
        .iter()
        .filter(|f| f.reference_mm[0].abs() < 0.1 * geometry.length_mm)
    {
        let stretch = field.deformation_gradient[0][0];
        let exact = law.uniaxial_cauchy_stress_mpa(stretch);
        let s = field.cauchy_stress_mpa;
        assert!(
            (s[0] - exact).abs() < 5e-3 * exact,
            "at {:?}: σxx {} vs {exact}",
            field.reference_mm,
            s[0]
        );
        assert!(
            s[1].abs() < 5e-3 * exact && s[2].abs() < 5e-3 * exact,
            "{s:?}"
        );
        checked += 1;
    }
    assert!(checked > 50);
    // The grip force is the force through the middle section: nominal stress × w × t.
    let middle = fields
        .iter()
        .min_by(|a, b| a.reference_mm[0].abs().total_cmp(&b.reference_mm[0].abs()))
        .unwrap();
    let nominal_n = law.uniaxial_nominal_stress_mpa(middle.deformation_gradient[0][0])
        * geometry.width_mm
        * geometry.thickness_mm;
    let force_n = solved.grip_force_n("x+")[0];
    assert!(
        (force_n - nominal_n).abs() < 5e-3 * nominal_n,
        "grip {force_n} N vs middle section {nominal_n} N"
    );
    let back = solved.grip_force_n("x-")[0];
    assert!(
        (force_n + back).abs() < 1e-8 * force_n,
        "equilibrium of the two grips"
    );
}

#[test]
fn newton_converges_quadratically() {
    let geometry = StripGeometry::plane_strain();
    let settings = NewtonSettings {
        load_steps: 4,
        relative_tolerance: 1e-13,
        ..NewtonSettings::default()
    };
    let solved = Solved::new(
        geometry.mesh().unwrap(),
        |s| s.pull_all(0.5 * geometry.length_mm),
        settings,
    );
    let equilibrium = &solved.equilibrium;
    let force_n = solved.grip_force_n("x+")[0];
    println!(
        "plane-strain strip, {} free DOFs, grip force {force_n:.6} N",
        equilibrium.free_dofs
    );
    for step in &equilibrium.steps {
        println!(
            "load factor {:.3}: residuals (N) {:?}, step lengths {:?}",
            step.load_factor, step.residuals_n, step.step_lengths
        );
    }
    // Quadratic: once in the basin (full steps, relative residual below 1e-4),
    // r_k+1 / f ≤ K (r_k / f)² with K < 1e3 (f the grip force; K ≈ 26 here, a linear rate
    // would give K ~ 1/r), down to the round-off floor.
    let mut pairs = 0;
    for step in &equilibrium.steps {
        assert!(step.residuals_n.len() <= 8, "{:?}", step.residuals_n);
        for (w, &length) in step.residuals_n.windows(2).zip(&step.step_lengths) {
            let (a, b) = (w[0] / force_n, w[1] / force_n);
            if length == 1.0 && a < 1e-4 && b > 1e-14 {
                assert!(b / (a * a) < 1e3, "r {a:e} → {b:e}: not quadratic");
                pairs += 1;
            }
        }
    }
    assert!(pairs >= 3, "{pairs} pairs in the quadratic range");
}

#[test]
fn plane_strain_strip_is_in_plane_strain_away_from_its_free_edges() {
    let geometry = StripGeometry::plane_strain();
    let solved = Solved::new(
        geometry.mesh().unwrap(),
        |s| s.pull_all(0.25 * geometry.length_mm),
        NewtonSettings::default(),
    );
    for field in solved
        .fields
        .iter()
        .filter(|f| f.reference_mm[1].abs() < 0.1 * geometry.width_mm)
    {
        let f = field.deformation_gradient;
        assert!(
            (f[1][1] - 1.0).abs() < 2e-3,
            "λ2 = {} at {:?}",
            f[1][1],
            field.reference_mm
        );
    }
}

#[test]
fn a_sheared_sheet_wrinkles_instead_of_carrying_compression() {
    let geometry = StripGeometry {
        length_mm: 40.0,
        width_mm: 80.0,
        thickness_mm: 1.0,
        element_size_mm: 4.0,
    };
    // x+ slides along y by 20 mm and pulls 2 mm: shear, compression along one diagonal.
    let shear = |s: &Specimen| {
        let mut clamps = s.pull_all(0.0);
        clamps[1].motion.translation_mm = [2.0, 20.0];
        clamps
    };
    let solved = Solved::new(geometry.mesh().unwrap(), shear, NewtonSettings::default());
    let last = solved.equilibrium.steps.last().unwrap();
    println!("states {:?}, residuals {:?}", last.states, last.residuals_n);
    assert!(last.states.wrinkled > 0, "{:?}", last.states);
    let largest = solved
        .fields
        .iter()
        .map(|f| {
            f.cauchy_stress_mpa[0]
                .abs()
                .max(f.cauchy_stress_mpa[1].abs())
        })
        .fold(0.0, f64::max);
    // Compression only through the residual stiffness ε of wrinkled and slack points.
    let eps = Wrinkling::default().residual_stiffness;
    for field in &solved.fields {
        let (_, minor) = membrane::constitutive::principal_values(&field.cauchy_stress_mpa);
        let limit = if field.state == MembraneState::Taut {
            1e-6
        } else {
            2.0 * eps
        };
        assert!(
            minor > -limit * largest,
            "compression {minor} MPa ({:?}) at {:?}",
            field.state,
            field.reference_mm
        );
    }
}
