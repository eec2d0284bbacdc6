//! Model discrimination from the whole field, noise-free (issue 25): the default cruciform solved
//! by finite elements under the paper's Smactane law (`material::InvariantLaw::smactane()`:
//! Lambert-Diani-Rey with f of degree 2, Table 3, and g of degree 2, Table 4 (ii)) at equibiaxial
//! grip stretches up to 2.4, its section cuts and tapered ramps (`common/cruciform.rs`, as
//! `vfm_structure.rs`), fitted and ranked by the field route's own code (`FitJob::run`: BIC,
//! identifiability) over the field route's default models and the families the paper discusses.

use crate::cruciform;

use cruciform::{observations, ramp_quadratures, smactane_gaps, solved_frames, GRID_STEP_MM};
use identifier::field_route::{FieldFits, FitJob};
use identifier::models::Model;
use identifier::online::OnlineConfig;
use identifier::reach::Reach;
use identifier::vfm::compile;
use identifier::virtual_work::Equations;
use material::InvariantLaw;

/// Equibiaxial grip stretches: the arms go far beyond 100 % strain (λ ≈ 3 at the cuts), the
/// central square, held by the four arms, stays near λ = 1.3.
const GRIP_STRETCHES: [(f64, f64); 5] =
    [(1.2, 1.2), (1.5, 1.5), (1.8, 1.8), (2.1, 2.1), (2.4, 2.4)];

const LDR: Model = Model::LambertDianiRey {
    f_degree: 2,
    g_degree: 2,
};

/// The field route's default models (the run's `[identifier] models`), and the families the
/// paper compares: Ogden with two terms (Mooney-Rivlin's form with free exponents) and
/// Lambert-Diani-Rey with the paper's n = 1 too.
fn models() -> Vec<Model> {
    let mut models = OnlineConfig::default().models;
    for extra in [
        Model::Ogden(2),
        Model::LambertDianiRey {
            f_degree: 1,
            g_degree: 1,
        },
    ] {
        if !models.contains(&extra) {
            models.push(extra);
        }
    }
    models
}

/// Smactane's coefficients as Lambert-Diani-Rey 2,2 parameters (a0..a2, b0..b2).
fn truth() -> Vec<f64> {
    let law = InvariantLaw::smactane();
    [law.f.coefficients(), law.g.coefficients()].concat()
}

/// What the field says on one mesh: the ranked fits and their equations.
struct Evidence {
    fits: FieldFits,
    equations: Equations,
}

impl Evidence {
    /// The field on a mesh of `element_size_mm`, its nonlinear fits started where `earlier`'s
    /// ended (as the route refits on line, [`FitJob::warm_starts`]).
    fn of(element_size_mm: f64, earlier: Option<&Evidence>) -> Evidence {
        let law = InvariantLaw::smactane();
        let (mesh, frames) = solved_frames(&law, &GRIP_STRETCHES, element_size_mm, GRID_STEP_MM);
        let probe = membrane::Probe::new(&mesh);
        let ramps = ramp_quadratures(&frames, &|x| probe.locate(x).is_some());
        let equations = compile(&observations(&frames, Some(&ramps))).unwrap();
        let fits = FitJob {
            equations: equations.clone(),
            // Each frame's four grip forces, each balanced by a cut and two ramps.
            forces: 4 * frames.len(),
            models: models(),
            frames: frames.len(),
            reach: Reach::of_grids(frames.iter().map(|f| &f.grid)),
            last_frame_id: None,
            warm_starts: earlier.map_or(vec![], |e| {
                e.fits
                    .fits
                    .iter()
                    .map(|f| (f.model.clone(), f.fit.params.clone()))
                    .collect()
            }),
        }
        .run();
        Evidence { fits, equations }
    }

    /// RMS over the equations of (computed − measured) / measured grip force.
    fn relative_rms(&self, model: &Model, params: &[f64]) -> f64 {
        let computed = self.equations.forces_n(model, params).unwrap();
        let measured = self.equations.measured_n();
        let sum: f64 = computed
            .iter()
            .zip(measured)
            .map(|(c, m)| ((c - m) / m).powi(2))
            .sum();
        (sum / measured.len() as f64).sqrt()
    }

    fn fit_of(&self, model: &Model) -> &identifier::field_route::FieldFit {
        self.fits
            .fits
            .iter()
            .find(|f| f.model == *model)
            .unwrap_or_else(|| panic!("{model} not fitted: {:?}", self.fits.refused))
    }

    fn report(&self, mesh: &str) {
        println!(
            "{mesh}: reach (max λ1, max λ2) {:.3?}; true law's relative RMS {:.3e}",
            self.fits.reach.max_stretches,
            self.relative_rms(&LDR, &truth())
        );
        for (rank, f) in self.fits.fits.iter().enumerate() {
            println!(
                "  {} {}: BIC {:.1}, AIC {:.1}, relative RMS {:.3e}, condition {:.1}{}",
                rank + 1,
                f.model,
                f.bic,
                f.aic,
                self.relative_rms(&f.model, &f.fit.params),
                f.fit.condition,
                if f.ranked() { "" } else { ", not identified" }
            );
        }
        for (model, why) in &self.fits.refused {
            println!("  refused {model}: {why}");
        }
    }
}

/// The worst relative gap between the identified law's nominal stress and Smactane's over the
/// states the field reached: uniaxial up to its largest major stretch, equibiaxial up to its
/// largest minor one, pure shear (I1 = I2) up to the largest I2 of its nodes (beyond, g is
/// extrapolated: the arms' uniaxial states reach I1 ≈ 21 but I2 ≈ 9 only). Each case's worst.
fn stress_gaps(model: &Model, params: &[f64], evidence: &Evidence) -> [f64; 3] {
    let reach = evidence.fits.reach.max_stretches;
    let max_i2 = evidence
        .equations
        .stretches()
        .iter()
        .map(|&[l1, l2]| material::invariants([l1, l2, 1.0 / (l1 * l2)]).1)
        .fold(3.0, f64::max);
    // λ² + 1 + λ⁻² = I2.
    let x = max_i2 - 1.0;
    let pure_shear_reach = (0.5 * (x + (x * x - 4.0).sqrt())).sqrt();
    smactane_gaps(model, params, [reach[0], reach[1], pure_shear_reach])
}

/// The field's evidence rejects Mooney-Rivlin on a Smactane specimen beyond 100 % strain and
/// ranks Smactane's own family first, on two meshes (the ranking is not the mesh's).
///
/// Measured when written (1 mm grid, 5 frames, 60 equations, 8 models; 22-29 s in release on
/// a machine shared with other builds):
/// the field reached max λ1 4.52 (the fillets; ≈ 3.0 at the cuts), max λ2 1.305 (the centre,
/// which the arms hold back). BIC ranking on 10 mm and 5 mm elements alike: LDR 2,2 (−167.2,
/// −222.1), Ogden 2 (−49.3, −85.3), LDR 1,1 (−35.6, −9.7), Mooney-Rivlin (225.6, 190.1),
/// Hart-Smith, Yeoh, neo-Hookean, Gent (not identified: Jm → ∞, its neo-Hookean limit).
/// Relative RMS of the force gaps: LDR 2,2 5.5e-4 and 3.8e-4, Mooney-Rivlin 2.23e-2 and 1.71e-2
/// (ratio 40 and 45; BIC worse by 393 and 412); the true law's own gap (the discretisation
/// error) 1.03e-2 and 2.7e-3: LDR 2,2 fits below it, its parameters absorb part of the mesh's
/// error. No identifiability or Drucker rule rejects Mooney-Rivlin (condition 3.4, both
/// parameters far above 2σ): its BIC and force residual do. LDR 2,2's nominal stresses against
/// Smactane's over the states reached, 5 mm (10 mm): uniaxial to λ 4.53 within 8.7e-3
/// (3.2e-3), equibiaxial to 1.305 within 4.3e-3 (1.3e-2); pure shear to its largest I2 within
/// 3.8e-2 (0.24): the field holds no I1 = I2 states at large strain.
#[test]
fn the_field_rejects_mooney_rivlin_beyond_100_percent_and_ranks_smactane_s_family_first() {
    let coarse = Evidence::of(10.0, None);
    let fine = Evidence::of(5.0, Some(&coarse));
    coarse.report("10 mm elements");
    fine.report("5 mm elements");
    for evidence in [&coarse, &fine] {
        let reach = evidence.fits.reach.max_stretches;
        // The arms beyond 100 % strain.
        assert!(reach[0] > 3.0, "{reach:?}");
        let best = &evidence.fits.fits[0];
        let mooney = evidence.fit_of(&Model::Mooney);
        assert!(best.ranked());
        assert_ne!(best.model, Model::Mooney);
        let (best_rms, mooney_rms) = (
            evidence.relative_rms(&best.model, &best.fit.params),
            evidence.relative_rms(&Model::Mooney, &mooney.fit.params),
        );
        assert!(mooney_rms > 10.0 * best_rms, "{mooney_rms} {best_rms}");
        assert!(mooney.bic > best.bic + 100.0, "{} {}", mooney.bic, best.bic);
        assert_eq!(best.model, LDR);
    }
    // Smactane's family, identified: its stresses over the states reached, on the fine mesh
    // (on the coarse one its equibiaxial stress is off by 1.3 %: the mesh's own error).
    for (mesh, evidence) in [("10 mm", &coarse), ("5 mm", &fine)] {
        let gaps = stress_gaps(&LDR, &evidence.fit_of(&LDR).fit.params, evidence)
            .map(|g| format!("{g:.2e}"));
        println!(
            "{mesh}: LDR 2,2's worst nominal-stress gaps to Smactane (uniaxial, equibiaxial, \
             pure shear): {gaps:.2?}"
        );
    }
    // Uniaxial and equibiaxial within 1 %; pure shear (I1 = I2) is not a state the cruciform's
    // field holds beyond small strains (its arms: I1 far above I2), reported only.
    let gaps = stress_gaps(&LDR, &fine.fit_of(&LDR).fit.params, &fine);
    assert!(gaps[0] < 0.01 && gaps[1] < 0.01, "{gaps:?}");
    // The mesh does not decide: the true law's own gap (the discretisation error) falls with
    // the element size, Mooney-Rivlin's misfit does not.
    let true_gap = |e: &Evidence| e.relative_rms(&LDR, &truth());
    let mooney_gap =
        |e: &Evidence| e.relative_rms(&Model::Mooney, &e.fit_of(&Model::Mooney).fit.params);
    assert!(true_gap(&fine) < true_gap(&coarse) / 2.0);
    assert!(mooney_gap(&fine) > 4.0 * true_gap(&fine));
}
