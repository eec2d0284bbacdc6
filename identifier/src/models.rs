//! The catalogue of incompressible potentials (Table 2 of the paper, plus the usual others).
//!
//! Every model gives the in-plane principal Cauchy stresses of a plane-stress state (σ3 = 0),
//! which covers the three load cases. Invariant models do it through W1 = ∂W/∂I1 and
//! W2 = ∂W/∂I2: σ_k = 2 W1 (λ_k² − λ3²) − 2 W2 (λ_k⁻² − λ3⁻²); Ogden through
//! σ_k = Σ μ_p (λ_k^α_p − λ3^α_p). All moduli are in MPa.
//!
//! Concrete choices where Table 2 leaves freedom:
//! - `isihara`: as printed in Table 2, W = C1 (I1−3) + C2 (I2−3)² + C3 (I2−3) (the form of
//!   Isihara's original paper, C10, C20, C01, is `rivlin:10,20,01`).
//! - `rivlin-saunders`: W = C1 (I1−3) + F(I2−3) with F(x) = C2 x + C3 x² + C4 x³ (F(0) = 0).
//! - `alexander`: μ/2 absorbed: W1 = C1 exp(k (I1−3)²), W2 = C2/(I2−3+γ) + C3.
//! - `hart-smith`: W1 = G exp(k1 (I1−3)²), W2 = G k2 / I2.
//! - `gent`: W = −(μ Jm/2) ln(1 − (I1−3)/Jm); `arruda-boyce`: exact inverse Langevin, λm² = N.
//! - `lambert-diani-rey`: the paper's W1 = exp Σ a_i (I1−3)^i, W2 = exp Σ b_i (I2−3)^i (eqs 22, 25).

use std::fmt;

/// One potential of the catalogue.
#[derive(Clone, Debug, PartialEq)]
pub enum Model {
    NeoHookean,
    Mooney,
    /// Rivlin series with the chosen (i, j) terms C_ij (I1−3)^i (I2−3)^j.
    Rivlin(Vec<(u32, u32)>),
    Isihara,
    RivlinSaunders,
    GentThomas,
    Biderman,
    HartSmith,
    Alexander,
    Yeoh,
    /// Ogden with N terms.
    Ogden(usize),
    Gent,
    ArrudaBoyce,
    /// Exponential f and g with the given polynomial degrees (n of Tables 3 and 4).
    LambertDianiRey {
        f_degree: usize,
        g_degree: usize,
    },
}

/// Default Rivlin terms when none are given: C10, C01, C20, C11.
pub const DEFAULT_RIVLIN_TERMS: [(u32, u32); 4] = [(1, 0), (0, 1), (2, 0), (1, 1)];
/// The Rivlin terms (ij of C_ij) of the 3-, 5- and 9-constant Mooney-Rivlin forms of FE codes
/// (`mooney-rivlin:3|5|9`; `mooney-rivlin:2` is [`Model::Mooney`]).
pub const MOONEY_RIVLIN_TERMS: [(usize, &[(u32, u32)]); 3] = [
    (3, &[(1, 0), (0, 1), (1, 1)]),
    (5, &[(1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]),
    (
        9,
        &[
            (1, 0),
            (0, 1),
            (2, 0),
            (1, 1),
            (0, 2),
            (3, 0),
            (2, 1),
            (1, 2),
            (0, 3),
        ],
    ),
];
/// Highest Ogden term count accepted.
pub const MAX_OGDEN_TERMS: usize = 6;

impl Model {
    /// The models `--model all` fits.
    pub fn all() -> Vec<Model> {
        vec![
            Model::NeoHookean,
            Model::Mooney,
            Model::Rivlin(DEFAULT_RIVLIN_TERMS.to_vec()),
            Model::Isihara,
            Model::RivlinSaunders,
            Model::GentThomas,
            Model::Biderman,
            Model::HartSmith,
            Model::Alexander,
            Model::Yeoh,
            Model::Ogden(2),
            Model::Ogden(3),
            Model::Gent,
            Model::ArrudaBoyce,
            Model::LambertDianiRey {
                f_degree: 2,
                g_degree: 2,
            },
        ]
    }

    /// Parses a model name: `mooney`, `rivlin:10,01,11`, `ogden:3` (or `ogden3`), `ldr:2,2`...
    pub fn parse(name: &str) -> Result<Model, ModelError> {
        let lower = name.trim().to_ascii_lowercase();
        let (head, arg) = match lower.split_once(':') {
            Some((h, a)) => (h.to_string(), Some(a.to_string())),
            None => (lower.clone(), None),
        };
        let no_arg = |m: Model| match &arg {
            None => Ok(m),
            Some(a) => Err(ModelError::NoArgument {
                name: name.into(),
                argument: a.clone(),
            }),
        };
        match head.as_str() {
            "neo-hookean" | "neohookean" | "neo_hookean" => no_arg(Model::NeoHookean),
            "mooney" | "mooney-rivlin" => match arg.as_deref() {
                None | Some("2") => Ok(Model::Mooney),
                // The Mooney-Rivlin forms of FE codes, by their count of constants.
                Some(n) => MOONEY_RIVLIN_TERMS
                    .iter()
                    .find(|(count, _)| count.to_string() == n.trim())
                    .map(|(_, terms)| Model::Rivlin(terms.to_vec()))
                    .ok_or_else(|| ModelError::MooneyRivlinConstants { name: name.into() }),
            },
            "isihara" => no_arg(Model::Isihara),
            "rivlin-saunders" | "rivlin_saunders" => no_arg(Model::RivlinSaunders),
            "gent-thomas" | "gent_thomas" => no_arg(Model::GentThomas),
            "biderman" => no_arg(Model::Biderman),
            "hart-smith" | "hart_smith" => no_arg(Model::HartSmith),
            "alexander" => no_arg(Model::Alexander),
            "yeoh" => no_arg(Model::Yeoh),
            "gent" => no_arg(Model::Gent),
            "arruda-boyce" | "arruda_boyce" => no_arg(Model::ArrudaBoyce),
            "rivlin" => match arg {
                None => Ok(Model::Rivlin(DEFAULT_RIVLIN_TERMS.to_vec())),
                Some(a) => {
                    let mut terms = Vec::new();
                    for t in a.split(',') {
                        let t = t.trim();
                        let bytes = t.as_bytes();
                        if bytes.len() != 2 || !bytes.iter().all(u8::is_ascii_digit) {
                            return Err(ModelError::RivlinTermDigits {
                                name: name.into(),
                                term: t.into(),
                            });
                        }
                        let ij = ((bytes[0] - b'0') as u32, (bytes[1] - b'0') as u32);
                        if ij == (0, 0) || terms.contains(&ij) {
                            return Err(ModelError::RivlinTermRepeated {
                                name: name.into(),
                                term: t.into(),
                            });
                        }
                        terms.push(ij);
                    }
                    Ok(Model::Rivlin(terms))
                }
            },
            "lambert-diani-rey" | "ldr" => match arg {
                None => Ok(Model::LambertDianiRey {
                    f_degree: 2,
                    g_degree: 2,
                }),
                Some(a) => {
                    let parts: Vec<Result<usize, _>> =
                        a.split(',').map(|s| s.trim().parse::<usize>()).collect();
                    match parts.as_slice() {
                        [Ok(f), Ok(g)] if *f <= 4 && *g <= 4 => Ok(Model::LambertDianiRey {
                            f_degree: *f,
                            g_degree: *g,
                        }),
                        _ => Err(ModelError::LdrDegrees { name: name.into() }),
                    }
                }
            },
            _ if head.starts_with("ogden") => {
                let n_text = arg.unwrap_or_else(|| head.trim_start_matches("ogden").to_string());
                let n = if n_text.is_empty() {
                    Ok(3)
                } else {
                    n_text.parse::<usize>()
                };
                match n {
                    Ok(n) if (1..=MAX_OGDEN_TERMS).contains(&n) => Ok(Model::Ogden(n)),
                    _ => Err(ModelError::OgdenTerms { name: name.into() }),
                }
            }
            _ => Err(ModelError::Unknown { name: name.into() }),
        }
    }

    /// Canonical name (parsable by [`Model::parse`]).
    pub fn name(&self) -> String {
        match self {
            Model::NeoHookean => "neo-hookean".into(),
            Model::Mooney => "mooney".into(),
            Model::Rivlin(t) => {
                let terms: Vec<String> = t.iter().map(|(i, j)| format!("{i}{j}")).collect();
                format!("rivlin:{}", terms.join(","))
            }
            Model::Isihara => "isihara".into(),
            Model::RivlinSaunders => "rivlin-saunders".into(),
            Model::GentThomas => "gent-thomas".into(),
            Model::Biderman => "biderman".into(),
            Model::HartSmith => "hart-smith".into(),
            Model::Alexander => "alexander".into(),
            Model::Yeoh => "yeoh".into(),
            Model::Ogden(n) => format!("ogden:{n}"),
            Model::Gent => "gent".into(),
            Model::ArrudaBoyce => "arruda-boyce".into(),
            Model::LambertDianiRey { f_degree, g_degree } => {
                format!("lambert-diani-rey:{f_degree},{g_degree}")
            }
        }
    }

    /// Parameter names (MPa for moduli, dimensionless otherwise).
    pub fn param_names(&self) -> Vec<String> {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        match self {
            Model::NeoHookean => s(&["C10"]),
            Model::Mooney => s(&["C10", "C01"]),
            Model::Rivlin(t) => t.iter().map(|(i, j)| format!("C{i}{j}")).collect(),
            Model::Isihara => s(&["C1", "C2", "C3"]),
            Model::RivlinSaunders => s(&["C1", "C2", "C3", "C4"]),
            Model::GentThomas => s(&["C1", "C2"]),
            Model::Biderman => s(&["C10", "C20", "C30", "C01"]),
            Model::HartSmith => s(&["G", "k1", "k2"]),
            Model::Alexander => s(&["C1", "k", "C2", "gamma", "C3"]),
            Model::Yeoh => s(&["C10", "C20", "C30"]),
            Model::Ogden(n) => (1..=*n)
                .map(|p| format!("mu{p}"))
                .chain((1..=*n).map(|p| format!("alpha{p}")))
                .collect(),
            Model::Gent => s(&["mu", "Jm"]),
            Model::ArrudaBoyce => s(&["mu", "N"]),
            Model::LambertDianiRey { f_degree, g_degree } => (0..=*f_degree)
                .map(|i| format!("a{i}"))
                .chain((0..=*g_degree).map(|i| format!("b{i}")))
                .collect(),
        }
    }

    /// For each parameter: is the stress linear in it when the others are held fixed
    /// (and jointly linear in all the flagged ones)?
    pub fn linear_params(&self) -> Vec<bool> {
        let n = self.param_names().len();
        match self {
            Model::HartSmith => vec![true, false, false],
            Model::Alexander => vec![true, false, true, false, true],
            Model::Ogden(k) => (0..2 * k).map(|i| i < *k).collect(),
            Model::Gent | Model::ArrudaBoyce => vec![true, false],
            Model::LambertDianiRey { .. } => vec![false; n],
            _ => vec![true; n],
        }
    }

    /// W1 = ∂W/∂I1 and W2 = ∂W/∂I2 in MPa, `None` outside the model's domain; `None` for Ogden.
    pub fn invariant_derivatives_mpa(&self, p: &[f64], i1: f64, i2: f64) -> Option<(f64, f64)> {
        let x = i1 - 3.0;
        let y = i2 - 3.0;
        let pair = match self {
            Model::NeoHookean => (p[0], 0.0),
            Model::Mooney => (p[0], p[1]),
            Model::Rivlin(terms) => {
                let mut w1 = 0.0;
                let mut w2 = 0.0;
                for (c, &(i, j)) in p.iter().zip(terms) {
                    if i > 0 {
                        w1 += c * i as f64 * x.powi(i as i32 - 1) * y.powi(j as i32);
                    }
                    if j > 0 {
                        w2 += c * j as f64 * x.powi(i as i32) * y.powi(j as i32 - 1);
                    }
                }
                (w1, w2)
            }
            Model::Isihara => (p[0], 2.0 * p[1] * y + p[2]),
            Model::RivlinSaunders => (p[0], p[1] + 2.0 * p[2] * y + 3.0 * p[3] * y * y),
            Model::GentThomas => (p[0], p[1] / i2),
            Model::Biderman => (p[0] + 2.0 * p[1] * x + 3.0 * p[2] * x * x, p[3]),
            Model::Yeoh => (p[0] + 2.0 * p[1] * x + 3.0 * p[2] * x * x, 0.0),
            Model::HartSmith => (p[0] * (p[1] * x * x).exp(), p[0] * p[2] / i2),
            Model::Alexander => {
                if p[3] <= 0.0 {
                    return None;
                }
                (p[0] * (p[1] * x * x).exp(), p[2] / (y + p[3]) + p[4])
            }
            Model::Gent => {
                let jm = p[1];
                if jm <= 0.0 || x >= jm {
                    return None;
                }
                (0.5 * p[0] / (1.0 - x / jm), 0.0)
            }
            Model::ArrudaBoyce => {
                let n = p[1];
                if n <= 0.0 {
                    return None;
                }
                let chain_stretch = (i1 / 3.0).sqrt();
                let beta = inverse_langevin(chain_stretch / n.sqrt())?;
                (p[0] * n.sqrt() * beta / (6.0 * chain_stretch), 0.0)
            }
            Model::LambertDianiRey { f_degree, .. } => {
                let (a, b) = p.split_at(f_degree + 1);
                let poly = |c: &[f64], t: f64| c.iter().rev().fold(0.0, |acc, &v| acc * t + v);
                (poly(a, x).exp(), poly(b, y).exp())
            }
            Model::Ogden(_) => return None,
        };
        (pair.0.is_finite() && pair.1.is_finite()).then_some(pair)
    }

    /// In-plane principal Cauchy stresses (σ1, σ2) in MPa with σ3 = 0, λ3 = 1/(λ1 λ2).
    /// `None` outside the model's domain (limiting chain extensibility, γ ≤ 0...).
    pub fn in_plane_cauchy_stress_mpa(
        &self,
        p: &[f64],
        stretch1: f64,
        stretch2: f64,
    ) -> Option<[f64; 2]> {
        debug_assert_eq!(p.len(), self.param_names().len());
        let stretch3 = 1.0 / (stretch1 * stretch2);
        let stress = if let Model::Ogden(n) = self {
            let (mu, alpha) = p.split_at(*n);
            let s = |l: f64| {
                mu.iter()
                    .zip(alpha)
                    .map(|(m, a)| m * (l.powf(*a) - stretch3.powf(*a)))
                    .sum::<f64>()
            };
            [s(stretch1), s(stretch2)]
        } else {
            let (i1, i2) = crate::law::invariants([stretch1, stretch2, stretch3]);
            let (w1, w2) = self.invariant_derivatives_mpa(p, i1, i2)?;
            let l3_sq = stretch3 * stretch3;
            let s = |l: f64| 2.0 * w1 * (l * l - l3_sq) - 2.0 * w2 * (1.0 / (l * l) - 1.0 / l3_sq);
            [s(stretch1), s(stretch2)]
        };
        (stress[0].is_finite() && stress[1].is_finite()).then_some(stress)
    }

    /// Nominal stress along the loaded direction of a load case, MPa (σ1/λ1, computed by
    /// [`Model::nominal_stress_at`]; `None` outside the model's domain).
    pub fn nominal_stress_mpa(
        &self,
        p: &[f64],
        case: crate::data::LoadCase,
        stretch: f64,
    ) -> Option<f64> {
        self.nominal_stress_at(p, &crate::kinematics::Kinematics::of(case, stretch), None)
    }
}

/// Why a model name was refused (the name as given).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("model `{name}`: takes no `:{argument}` argument")]
    NoArgument { name: String, argument: String },
    #[error("model `{name}`: Mooney-Rivlin takes 2, 3, 5 or 9 constants")]
    MooneyRivlinConstants { name: String },
    #[error("model `{name}`: Rivlin term `{term}` must be two digits ij, e.g. 10,01,11")]
    RivlinTermDigits { name: String, term: String },
    #[error("model `{name}`: Rivlin term `{term}` is 00 or repeated")]
    RivlinTermRepeated { name: String, term: String },
    #[error("model `{name}`: expected `ldr:NF,NG` with degrees 0..=4")]
    LdrDegrees { name: String },
    #[error("model `{name}`: Ogden term count must be 1..={MAX_OGDEN_TERMS}")]
    OgdenTerms { name: String },
    #[error(
        "unknown model `{name}`; expected one of neo-hookean, mooney (= mooney-rivlin:2), \
         mooney-rivlin:3|5|9, rivlin[:ij,..], isihara, \
         rivlin-saunders, gent-thomas, biderman, hart-smith, alexander, yeoh, ogden[:N], gent, \
         arruda-boyce, lambert-diani-rey[:NF,NG], or all"
    )]
    Unknown { name: String },
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// In a settings file, a model is its name (`ogden:3`), as [`Model::parse`] reads it.
impl serde::Serialize for Model {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Model {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Model, D::Error> {
        let name = String::deserialize(deserializer)?;
        Model::parse(&name).map_err(serde::de::Error::custom)
    }
}

/// Parses `NAME[,NAME...]` or `all`. Rivlin and LDR arguments use commas too, so a name is
/// split only before a token that starts with a letter.
pub fn parse_model_list(list: &str) -> Result<Vec<Model>, ModelError> {
    if list.trim().eq_ignore_ascii_case("all") {
        return Ok(Model::all());
    }
    let mut names: Vec<String> = Vec::new();
    for token in list.split(',') {
        let t = token.trim();
        match (t.chars().next(), names.last_mut()) {
            (Some(c), Some(last)) if !c.is_ascii_alphabetic() => {
                last.push(',');
                last.push_str(t);
            }
            _ => names.push(t.to_string()),
        }
    }
    names.iter().map(|n| Model::parse(n)).collect()
}

/// The models a fit ranks, as a user lists them (`yeoh,gent`, `ogden:3`, or `all`).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelList(pub Vec<Model>);

impl std::str::FromStr for ModelList {
    type Err = ModelError;

    fn from_str(list: &str) -> Result<ModelList, ModelError> {
        parse_model_list(list).map(ModelList)
    }
}

/// The names, comma-separated, as [`parse_model_list`] reads them back.
impl std::fmt::Display for ModelList {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self.0.iter().map(Model::name).collect();
        f.write_str(&names.join(","))
    }
}

/// Inverse Langevin function L⁻¹(x), |x| < 1, by safeguarded Newton (≤ 100 iterations).
pub fn inverse_langevin(x: f64) -> Option<f64> {
    if x.is_nan() || x.abs() >= 1.0 {
        return None;
    }
    if x.abs() < 1e-8 {
        return Some(3.0 * x);
    }
    let target = x.abs();
    let langevin = |b: f64| 1.0 / b.tanh() - 1.0 / b;
    // Bracket: L(b) < target at lo, > target at hi. L(b) ≈ 1 − 1/b for large b.
    let mut lo = 0.0_f64;
    let mut hi = 1.0 / (1.0 - target) + 1.0;
    let mut b = target * (3.0 - target * target) / (1.0 - target * target); // Cohen's approximation
    if !(b > lo && b < hi) {
        b = 0.5 * (lo + hi);
    }
    for _ in 0..100 {
        let value = langevin(b) - target;
        if value.abs() < 1e-14 {
            break;
        }
        if value < 0.0 {
            lo = b;
        } else {
            hi = b;
        }
        let sinh = b.sinh();
        let derivative = 1.0 / (b * b) - 1.0 / (sinh * sinh);
        let newton = b - value / derivative;
        b = if derivative.is_finite() && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
    }
    Some(b.copysign(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    #[test]
    fn names_round_trip() {
        for m in Model::all() {
            assert_eq!(Model::parse(&m.name()).unwrap(), m);
        }
        let list = parse_model_list("mooney,rivlin:10,01,11,ogden:2,ldr:3,1").unwrap();
        assert_eq!(Model::parse("mooney-rivlin:2").unwrap(), Model::Mooney);
        assert_eq!(
            Model::parse("Mooney-Rivlin:3").unwrap(),
            Model::Rivlin(vec![(1, 0), (0, 1), (1, 1)])
        );
        assert!(
            matches!(Model::parse("mooney-rivlin:9").unwrap(), Model::Rivlin(t) if t.len() == 9)
        );
        assert!(Model::parse("mooney-rivlin:4")
            .unwrap_err()
            .to_string()
            .contains("2, 3, 5 or 9"));
        assert_eq!(list.len(), 4);
        assert_eq!(list[1], Model::Rivlin(vec![(1, 0), (0, 1), (1, 1)]));
        assert_eq!(
            list[3],
            Model::LambertDianiRey {
                f_degree: 3,
                g_degree: 1
            }
        );
        assert!(Model::parse("foo").is_err());
    }

    #[test]
    fn ogden_reference_values_from_the_issue() {
        let p = [0.63, 0.0012, -0.01, 1.3, 5.0, -2.0];
        let m = Model::Ogden(3);
        let at = |l: f64| m.nominal_stress_mpa(&p, LoadCase::Uniaxial, l).unwrap();
        assert!((at(3.02) - 0.8854).abs() < 5e-4, "{}", at(3.02));
        assert!((at(6.15) - 2.7816).abs() < 5e-4, "{}", at(6.15));
    }

    #[test]
    fn small_strain_shear_moduli_agree() {
        // μ = 2 (C10 + C01) for Mooney, Σ μ α / 2 for Ogden, μ for Gent.
        let eps = 1e-6;
        let slope = |m: &Model, p: &[f64]| {
            m.nominal_stress_mpa(p, LoadCase::Uniaxial, 1.0 + eps)
                .unwrap()
                / eps
                / 3.0
        };
        assert!((slope(&Model::Mooney, &[0.2, 0.1]) - 0.6).abs() < 1e-4);
        assert!((slope(&Model::Ogden(1), &[0.3, 2.0]) - 0.3).abs() < 1e-4);
        assert!((slope(&Model::Gent, &[0.5, 40.0]) - 0.5).abs() < 1e-4);
        // Arruda-Boyce: μ0 = μ (√N/3) L⁻¹(1/√N) ≈ μ (1 + 3/(5N) + ...).
        let n = 8.0_f64;
        let mu0 = 0.5 * n.sqrt() / 3.0 * inverse_langevin(1.0 / n.sqrt()).unwrap();
        assert!((slope(&Model::ArrudaBoyce, &[0.5, n]) - mu0).abs() < 1e-4);
        assert!((mu0 / 0.5 - 1.0 - 3.0 / (5.0 * n)).abs() < 0.02);
    }

    #[test]
    fn inverse_langevin_inverts() {
        for &x in &[0.01, 0.3, 0.7, 0.95, 0.999] {
            let b = inverse_langevin(x).unwrap();
            assert!((1.0 / b.tanh() - 1.0 / b - x).abs() < 1e-10, "x = {x}");
        }
        assert!(inverse_langevin(1.0).is_none());
    }
}
