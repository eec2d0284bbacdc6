//! FE-ready coefficient cards of a fitted model: the Abaqus `*HYPERELASTIC` keyword and the
//! Ansys Mechanical APDL `TB,HYPER` table, incompressible (every D or d = 0; Abaqus/Standard
//! then needs hybrid elements), in the identifier's units (MPa with mm and N).
//!
//! Conventions used (checked against the manuals, as cited):
//! - Abaqus polynomial family, U = Σ C_ij (Ī1 − 3)^i (Ī2 − 3)^j + Σ (J − 1)^2i / D_i,
//!   μ0 = 2 (C10 + C01), D = 0 incompressible ("Strain energy potential", Abaqus/CAE User's
//!   Guide 2017, abaqus-docs.mit.edu/2017/English/SIMACAEGSARefMap/simagsa-c-matstrainenergy.htm):
//!   `NEO HOOKE` (C10, D1), `MOONEY-RIVLIN` (C10, C01, D1), `REDUCED POLYNOMIAL, N` (C10 … CN0,
//!   D1 … DN), `POLYNOMIAL, N` (C10, C01, C20, C11, C02, C30, … then D1 … DN), at most 8
//!   values a data line.
//! - Abaqus Ogden, U = Σ 2 μi / αi² (λ̄1^αi + λ̄2^αi + λ̄3^αi − 3), μ0 = Σ μi: the same form
//!   as Altair's MATX82 (2021.help.altair.com, "MATX82 Bulk Data Entry", W = Σ 2μi/αi² (…)).
//!   The identifier's W = Σ μp/αp (…) gives μi(Abaqus) = μp αp / 2, αi = αp.
//! - Abaqus `ARRUDA-BOYCE` (μ, λm, D): λm = √N; Abaqus's five-term series of the inverse
//!   Langevin function, the identifier's exact one.
//! - Ansys (Mechanical APDL Material Reference 4.6, ansyshelp.ansys.com …/ans_mat/aQw8sq22dldm.html,
//!   and the Structural Analysis Guide 8.4.1.2 examples): `NEO` (μ = 2 C10, d), `MOONEY`
//!   (C10, C01, d), `YEOH` (C10 … CN0, d1 … dN), `POLY` (C10, C01, C20, C11, C02, … then
//!   d1 … dN), `OGDEN` (μ1, α1, μ2, α2, … then d1 … dN, W = Σ μi/αi (…): the identifier's own
//!   μ and α), `GENT` (μ, Jm, d), `BOYCE` (μ, λL = √N, d).
//!
//! Models outside these families (Gent-Thomas, Hart-Smith, Alexander, Lambert-Diani-Rey;
//! Gent in Abaqus) have no card: a user subroutine would be needed.

use crate::fit::Fit;
use crate::initial_modulus::initial_shear_modulus_mpa;
use crate::models::Model;
use std::path::{Path, PathBuf};

/// A card file that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot write: {message}")]
pub struct CardsError {
    pub path: String,
    pub message: String,
}

/// Writes each fit's cards into `dir` (created): `abaqus_<model>.inp`, `ansys_<model>.mac`
/// (the model's name with every character but letters and digits as `_`); returns the paths.
pub fn write_cards(dir: &Path, fits: &[Fit]) -> Result<Vec<PathBuf>, CardsError> {
    let fail = |path: &Path, e: std::io::Error| CardsError {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| fail(dir, e))?;
    let mut written = Vec::new();
    for fit in fits {
        let stem: String = fit
            .model
            .name()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let cards = fe_cards(fit, initial_shear_modulus_mpa(&fit.model, &fit.params));
        for (card, name) in [
            (cards.abaqus, format!("abaqus_{stem}.inp")),
            (cards.ansys, format!("ansys_{stem}.mac")),
        ] {
            if let Some(card) = card {
                let path = dir.join(name);
                std::fs::write(&path, card).map_err(|e| fail(&path, e))?;
                written.push(path);
            }
        }
    }
    Ok(written)
}

/// The two cards of a fit, `None` where the code has no such model.
#[derive(Clone, Debug, PartialEq)]
pub struct FeCards {
    pub abaqus: Option<String>,
    pub ansys: Option<String>,
}

/// The cards of `fit`, headed by comments naming the model, μ0 and, if any, the warning
/// that its parameters are not identifiable.
pub fn fe_cards(fit: &Fit, initial_shear_modulus_mpa: Option<f64>) -> FeCards {
    let mut head = vec![format!(
        "dicstream identify: {}, units MPa (N, mm), incompressible (D = 0)",
        fit.model.name()
    )];
    if let Some(mu0) = initial_shear_modulus_mpa {
        head.push(format!("initial shear modulus mu0 = {mu0:.6e} MPa"));
    }
    if let Some(w) = fit.identifiability.warning() {
        head.push(format!("WARNING: {w}"));
    }
    let comment =
        |prefix: &str| -> String { head.iter().map(|l| format!("{prefix}{l}\n")).collect() };
    FeCards {
        abaqus: abaqus(&fit.model, &fit.params).map(|card| comment("** ") + &card),
        ansys: ansys(&fit.model, &fit.params).map(|card| comment("! ") + &card),
    }
}

/// The model as Rivlin polynomial terms ((i, j), C_ij), where it is one.
fn polynomial_terms(model: &Model, p: &[f64]) -> Option<Vec<((u32, u32), f64)>> {
    let ij: Vec<(u32, u32)> = match model {
        Model::NeoHookean => vec![(1, 0)],
        Model::Mooney => vec![(1, 0), (0, 1)],
        Model::Rivlin(terms) => terms.clone(),
        Model::Yeoh => vec![(1, 0), (2, 0), (3, 0)],
        Model::Biderman => vec![(1, 0), (2, 0), (3, 0), (0, 1)],
        // W1 = C1, W2 = 2 C2 (I2 − 3) + C3.
        Model::Isihara => vec![(1, 0), (0, 2), (0, 1)],
        // W1 = C1, W2 = C2 + 2 C3 (I2 − 3) + 3 C4 (I2 − 3)².
        Model::RivlinSaunders => vec![(1, 0), (0, 1), (0, 2), (0, 3)],
        _ => return None,
    };
    Some(ij.into_iter().zip(p.iter().copied()).collect())
}

/// C_ij of `terms` in the codes' order for order `n`: C10, C01, C20, C11, C02, C30, …
fn polynomial_order(terms: &[((u32, u32), f64)], n: u32) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..=n {
        for i in (0..=k).rev() {
            let c = terms
                .iter()
                .find(|(t, _)| *t == (i, k - i))
                .map_or(0.0, |t| t.1);
            out.push(c);
        }
    }
    out
}

/// A Rivlin polynomial as the codes name it.
enum PolynomialForm {
    NeoHookean {
        c10: f64,
    },
    MooneyRivlin {
        c10: f64,
        c01: f64,
    },
    /// C10 … CN0 (Yeoh for N = 3).
    Reduced(Vec<f64>),
    /// Order N and C10, C01, C20, C11, C02, C30, …
    Full(u32, Vec<f64>),
}

/// The codes' form of a model that is a Rivlin polynomial.
fn polynomial_form(model: &Model, p: &[f64]) -> Option<PolynomialForm> {
    let terms = polynomial_terms(model, p)?;
    let n = terms.iter().map(|((i, j), _)| i + j).max()?;
    let only = |set: &[(u32, u32)]| terms.iter().all(|(t, _)| set.contains(t));
    let c = polynomial_order(&terms, n);
    Some(if only(&[(1, 0)]) {
        PolynomialForm::NeoHookean { c10: c[0] }
    } else if only(&[(1, 0), (0, 1)]) {
        PolynomialForm::MooneyRivlin {
            c10: c[0],
            c01: c[1],
        }
    } else if terms.iter().all(|((_, j), _)| *j == 0) {
        PolynomialForm::Reduced(
            (1..=n)
                .map(|i| {
                    terms
                        .iter()
                        .find(|(t, _)| *t == (i, 0))
                        .map_or(0.0, |t| t.1)
                })
                .collect(),
        )
    } else {
        PolynomialForm::Full(n, c)
    })
}

/// `values` then `count` zeros (the incompressible D or d).
fn with_zeros(mut values: Vec<f64>, count: usize) -> Vec<f64> {
    values.extend(std::iter::repeat_n(0.0, count));
    values
}

fn number(v: f64) -> String {
    format!("{v:.8e}")
}

/// Abaqus data lines: at most 8 values a line.
fn abaqus_lines(values: &[f64]) -> String {
    values
        .chunks(8)
        .map(|c| c.iter().map(|&v| number(v)).collect::<Vec<_>>().join(", ") + "\n")
        .collect()
}

fn abaqus(model: &Model, p: &[f64]) -> Option<String> {
    if let Some(form) = polynomial_form(model, p) {
        return match form {
            PolynomialForm::NeoHookean { c10 } => Some(format!(
                "*HYPERELASTIC, NEO HOOKE\n{}",
                abaqus_lines(&[c10, 0.0])
            )),
            PolynomialForm::MooneyRivlin { c10, c01 } => Some(format!(
                "*HYPERELASTIC, MOONEY-RIVLIN\n{}",
                abaqus_lines(&[c10, c01, 0.0])
            )),
            PolynomialForm::Reduced(c) => Some(format!(
                "*HYPERELASTIC, REDUCED POLYNOMIAL, N={}\n{}",
                c.len(),
                abaqus_lines(&with_zeros(c.clone(), c.len()))
            )),
            // Abaqus takes polynomials up to N = 6.
            PolynomialForm::Full(n, _) if n > 6 => None,
            PolynomialForm::Full(n, c) => Some(format!(
                "*HYPERELASTIC, POLYNOMIAL, N={n}\n{}",
                abaqus_lines(&with_zeros(c, n as usize))
            )),
        };
    }
    match model {
        Model::Ogden(n) => {
            let (mu, alpha) = p.split_at(*n);
            let v = mu.iter().zip(alpha).flat_map(|(m, a)| [m * a / 2.0, *a]);
            let v = with_zeros(v.collect(), *n);
            Some(format!("*HYPERELASTIC, OGDEN, N={n}\n{}", abaqus_lines(&v)))
        }
        Model::ArrudaBoyce => Some(format!(
            "*HYPERELASTIC, ARRUDA-BOYCE\n{}",
            abaqus_lines(&[p[0], p[1].sqrt(), 0.0])
        )),
        _ => None,
    }
}

/// `TBDATA` commands: at most 6 values each, from position 1.
fn tbdata(values: &[f64]) -> String {
    values
        .chunks(6)
        .enumerate()
        .map(|(k, c)| {
            let cells: Vec<String> = c.iter().map(|&v| number(v)).collect();
            format!("TBDATA,{},{}\n", 6 * k + 1, cells.join(","))
        })
        .collect()
}

fn ansys(model: &Model, p: &[f64]) -> Option<String> {
    if let Some(form) = polynomial_form(model, p) {
        return Some(match form {
            PolynomialForm::NeoHookean { c10 } => {
                format!("TB,HYPER,1,,,NEO\n{}", tbdata(&[2.0 * c10, 0.0]))
            }
            PolynomialForm::MooneyRivlin { c10, c01 } => {
                format!("TB,HYPER,1,,2,MOONEY\n{}", tbdata(&[c10, c01, 0.0]))
            }
            PolynomialForm::Reduced(c) => format!(
                "TB,HYPER,1,,{},YEOH\n{}",
                c.len(),
                tbdata(&with_zeros(c.clone(), c.len()))
            ),
            PolynomialForm::Full(n, c) => format!(
                "TB,HYPER,1,,{n},POLY\n{}",
                tbdata(&with_zeros(c, n as usize))
            ),
        });
    }
    match model {
        Model::Ogden(n) => {
            let (mu, alpha) = p.split_at(*n);
            let v = mu.iter().zip(alpha).flat_map(|(m, a)| [*m, *a]);
            let v = with_zeros(v.collect(), *n);
            Some(format!("TB,HYPER,1,,{n},OGDEN\n{}", tbdata(&v)))
        }
        Model::Gent => Some(format!("TB,HYPER,1,,,GENT\n{}", tbdata(&[p[0], p[1], 0.0]))),
        Model::ArrudaBoyce => Some(format!(
            "TB,HYPER,1,,,BOYCE\n{}",
            tbdata(&[p[0], p[1].sqrt(), 0.0])
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cards_follow_each_codes_order_and_scaling() {
        let mr = abaqus(&Model::Mooney, &[0.2, 0.05]).unwrap();
        assert_eq!(
            mr,
            "*HYPERELASTIC, MOONEY-RIVLIN\n2.00000000e-1, 5.00000000e-2, 0.00000000e0\n"
        );
        let neo = ansys(&Model::NeoHookean, &[0.2]).unwrap();
        assert_eq!(
            neo,
            "TB,HYPER,1,,,NEO\nTBDATA,1,4.00000000e-1,0.00000000e0\n"
        );
        // Ogden: Abaqus μ = μp αp / 2 (same μ0 = Σ μ), Ansys the identifier's μp.
        let p = [0.63, 0.0012, -0.01, 1.3, 5.0, -2.0];
        let a = abaqus(&Model::Ogden(3), &p).unwrap();
        let lines: Vec<&str> = a.lines().collect();
        assert_eq!(lines[0], "*HYPERELASTIC, OGDEN, N=3");
        let first: Vec<f64> = lines[1].split(", ").map(|v| v.parse().unwrap()).collect();
        assert_eq!(first.len(), 8, "8 values a data line");
        assert!((first[0] - 0.4095).abs() < 1e-12 && first[1] == 1.3);
        assert_eq!(lines[2], "0.00000000e0", "D3 on the next line");
        let mu0_abaqus: f64 = first[0] + first[2] + first[4];
        assert!((mu0_abaqus - 0.4225).abs() < 1e-12);
        let s = ansys(&Model::Ogden(3), &p).unwrap();
        assert!(
            s.starts_with("TB,HYPER,1,,3,OGDEN\nTBDATA,1,6.30000000e-1,1.30000000e0,"),
            "{s}"
        );
        assert!(s.contains("\nTBDATA,7,"), "{s}");
        // A Rivlin polynomial in the codes' order, absent terms zero.
        let r = abaqus(&Model::Rivlin(vec![(1, 0), (1, 1)]), &[0.2, 0.003]).unwrap();
        assert!(r.starts_with("*HYPERELASTIC, POLYNOMIAL, N=2\n2.00000000e-1, 0.00000000e0, 0.00000000e0, 3.00000000e-3, 0.00000000e0, 0.00000000e0, 0.00000000e0\n"), "{r}");
        let y = ansys(&Model::Yeoh, &[0.2, -0.01, 0.001]).unwrap();
        assert!(
            y.starts_with(
                "TB,HYPER,1,,3,YEOH\nTBDATA,1,2.00000000e-1,-1.00000000e-2,1.00000000e-3,0"
            ),
            "{y}"
        );
        assert!(abaqus(&Model::Gent, &[0.4, 50.0]).is_none());
        assert!(ansys(&Model::Gent, &[0.4, 50.0]).is_some());
        assert!(abaqus(&Model::HartSmith, &[0.2, 0.001, 0.5]).is_none());
    }
}
