//! Load cases, general biaxial states, their kinematics, and the CSV readers
//! (`stretch,nominal_stress_mpa` per canonical case; `lambda1,lambda2,nominal_stress1_mpa,
//! nominal_stress2_mpa` for general biaxial states).
//!
//! Every datum is a homogeneous incompressible membrane state (plane stress): in-plane
//! principal stretches (λ1, λ2), the traction-free thickness λ3 = 1/(λ1 λ2) (σ3 = 0). With
//! W(I1, I2), I1 = λ1² + λ2² + λ3², I2 = λ1⁻² + λ2⁻² + λ3⁻², W1 = ∂W/∂I1, W2 = ∂W/∂I2, the
//! pressure eliminated by σ3 = 0:
//!
//! σ_k = 2 W1 (λ_k² − λ3²) − 2 W2 (λ_k⁻² − λ3⁻²),   P_k = σ_k / λ_k   (k = 1, 2).
//!
//! A [`BiaxialState`] measures both P1 and P2 and gives the fit two points: P1 at (λ1, λ2) and
//! P2 at (λ2, λ1) (same invariants, roles swapped; [`crate::gradient::Kinematics::in_plane`]).
//! The three canonical [`LoadCase`]s are the special paths λ2 = λ^(−1/2) (uniaxial), λ2 = λ
//! (equibiaxial), λ2 = 1 (pure shear) of a [`Curve`], which measures P1 alone.
//!
//! Stretch exactly 1.0 is the undeformed reference: both sides of eq. 19 vanish there, so it
//! carries no information on W (and would divide by zero in eqs 20, 23 and in relative
//! residuals). The reader accepts it and drops it, counting it in
//! [`Curve::reference_rows_dropped`]. Any stretch below 1.0 is an error (tension data only).

use crate::columns::{biaxial_rows, curve_rows, Specimen};
use crate::table::{Table, TableOptions};
use std::fmt;
use std::path::Path;

/// The three classical homogeneous tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LoadCase {
    /// Simple tension: λ1 = λ, λ2 = λ3 = λ^(−1/2).
    Uniaxial,
    /// Equibiaxial tension: λ1 = λ2 = λ, λ3 = λ^(−2).
    Equibiaxial,
    /// Pure shear (planar tension): λ1 = λ, λ2 = 1, λ3 = 1/λ.
    PureShear,
}

impl LoadCase {
    pub const ALL: [LoadCase; 3] = [
        LoadCase::Uniaxial,
        LoadCase::Equibiaxial,
        LoadCase::PureShear,
    ];

    /// Name used in tables and JSON keys.
    pub fn name(self) -> &'static str {
        match self {
            LoadCase::Uniaxial => "uniaxial",
            LoadCase::Equibiaxial => "equibiaxial",
            LoadCase::PureShear => "pure_shear",
        }
    }

    /// In-plane principal stretches (λ1, λ2) for the loaded stretch λ.
    pub fn in_plane_stretches(self, stretch: f64) -> (f64, f64) {
        assert!(
            stretch > 0.0 && stretch.is_finite(),
            "stretch must be positive, got {stretch}"
        );
        match self {
            LoadCase::Uniaxial => (stretch, 1.0 / stretch.sqrt()),
            LoadCase::Equibiaxial => (stretch, stretch),
            LoadCase::PureShear => (stretch, 1.0),
        }
    }

    /// The three principal stretches, λ1 λ2 λ3 = 1.
    pub fn stretches(self, stretch: f64) -> [f64; 3] {
        let (l1, l2) = self.in_plane_stretches(stretch);
        [l1, l2, 1.0 / (l1 * l2)]
    }

    /// Invariants (I1, I2) for the loaded stretch λ.
    pub fn invariants(self, stretch: f64) -> (f64, f64) {
        crate::law::invariants(self.stretches(stretch))
    }

    /// The path ratio ρ = ln λ2 / ln λ1 of the case: −1/2, 1, 0.
    pub fn path_ratio(self) -> f64 {
        match self {
            LoadCase::Uniaxial => -0.5,
            LoadCase::Equibiaxial => 1.0,
            LoadCase::PureShear => 0.0,
        }
    }

    /// The canonical case a state of path ratio `ratio` (ρ = ln λ2 / ln λ1, λ1 the larger
    /// stretch) is within `tolerance` of, if any.
    pub fn of_path_ratio(ratio: f64, tolerance: f64) -> Option<LoadCase> {
        LoadCase::ALL
            .into_iter()
            .find(|c| (ratio - c.path_ratio()).abs() < tolerance)
    }
}

/// What a group of fitted points is: a canonical curve, or the general biaxial states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DataGroup {
    Case(LoadCase),
    /// [`BiaxialState`]s, both directions.
    BiaxialGeneral,
}

impl DataGroup {
    /// Name used in tables and JSON keys.
    pub fn name(self) -> &'static str {
        match self {
            DataGroup::Case(case) => case.name(),
            DataGroup::BiaxialGeneral => "biaxial_general",
        }
    }
}

impl fmt::Display for DataGroup {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One measured homogeneous biaxial state: both in-plane stretches and both nominal stresses
/// (force over reference section, MPa), direction 3 traction-free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiaxialState {
    pub stretch1: f64,
    pub stretch2: f64,
    pub nominal_stress1_mpa: f64,
    pub nominal_stress2_mpa: f64,
}

impl BiaxialState {
    /// Thickness stretch λ3 = 1/(λ1 λ2).
    pub fn stretch3(&self) -> f64 {
        1.0 / (self.stretch1 * self.stretch2)
    }

    /// The larger in-plane stretch.
    pub fn max_stretch(&self) -> f64 {
        self.stretch1.max(self.stretch2)
    }

    /// ρ = ln λ_small / ln λ_large (`None` at the undeformed state).
    pub fn path_ratio(&self) -> Option<f64> {
        let (large, small) = if self.stretch1 >= self.stretch2 {
            (self.stretch1, self.stretch2)
        } else {
            (self.stretch2, self.stretch1)
        };
        (large > 1.0).then(|| small.ln() / large.ln())
    }

    /// Checks positivity and finiteness; the error says what is wrong.
    pub fn check(&self) -> Result<(), StateError> {
        let values = [
            ("lambda1", self.stretch1),
            ("lambda2", self.stretch2),
            ("nominal_stress1_mpa", self.nominal_stress1_mpa),
            ("nominal_stress2_mpa", self.nominal_stress2_mpa),
        ];
        for (name, v) in values {
            if !v.is_finite() {
                return Err(StateError::NotFinite { name, value: v });
            }
        }
        for (name, v) in &values[..2] {
            if *v <= 0.0 {
                return Err(StateError::NotPositive { name, value: *v });
            }
        }
        Ok(())
    }
}

/// A biaxial state that is not one.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StateError {
    #[error("{name} {value} is not a finite number")]
    NotFinite { name: &'static str, value: f64 },
    #[error("{name} {value} must be > 0")]
    NotPositive { name: &'static str, value: f64 },
}

/// The states that are canonical cases (path ratio within `tolerance`, see
/// [`LoadCase::of_path_ratio`]) as one curve per case with at least [`MIN_POINTS_PER_CURVE`]
/// points: loaded stretch the larger one and its nominal stress (equibiaxial: the means of
/// both directions), sorted by stretch (a repeated stretch keeps its first state). For the
/// curve views (plots) of a state set; fits take the states themselves.
pub fn canonical_curves(states: &[BiaxialState], tolerance: f64) -> Vec<Curve> {
    let mut curves = Vec::new();
    for case in LoadCase::ALL {
        let mut rows: Vec<(f64, f64)> = states
            .iter()
            .filter(|s| {
                s.path_ratio()
                    .and_then(|r| LoadCase::of_path_ratio(r, tolerance))
                    == Some(case)
            })
            .map(|s| match case {
                LoadCase::Equibiaxial => (
                    0.5 * (s.stretch1 + s.stretch2),
                    0.5 * (s.nominal_stress1_mpa + s.nominal_stress2_mpa),
                ),
                _ if s.stretch1 >= s.stretch2 => (s.stretch1, s.nominal_stress1_mpa),
                _ => (s.stretch2, s.nominal_stress2_mpa),
            })
            .collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        rows.dedup_by(|b, a| b.0 <= a.0);
        let (stretch, stress) = rows.into_iter().unzip();
        if let Ok(curve) = Curve::new(case, stretch, stress) {
            curves.push(curve);
        }
    }
    curves
}

/// The header of a general biaxial CSV as the identifier writes it.
pub const BIAXIAL_HEADER: &str = "lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa";

/// How to read a data file: its title lines ([`TableOptions`]) and what it lacks of the
/// specimen ([`Specimen`]: a gauge length for an extension, a section for a force).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadOptions {
    pub table: TableOptions,
    pub specimen: Specimen,
}

/// Reads a general biaxial CSV ([`BIAXIAL_HEADER`], or a machine's export of those columns:
/// [`crate::table`], [`crate::columns`]), one state a row.
pub fn read_biaxial_csv(
    path: &Path,
    options: &ReadOptions,
) -> Result<Vec<BiaxialState>, DataError> {
    biaxial_states(&Table::read(path, options.table)?)
}

/// Parses general biaxial CSV text: the header names the four columns; every row has four
/// finite numbers, positive stretches; the undeformed state (λ1 = λ2 = 1) is dropped (it
/// carries no information, as in [`Curve`]); at least [`MIN_POINTS_PER_CURVE`] states
/// remain. Errors name the line (counted from 1).
pub fn parse_biaxial_csv(
    text: &str,
    source_name: &str,
    options: &ReadOptions,
) -> Result<Vec<BiaxialState>, DataError> {
    biaxial_states(&Table::parse(text, source_name, options.table)?)
}

fn biaxial_states(table: &Table) -> Result<Vec<BiaxialState>, DataError> {
    let mut states = Vec::new();
    for (line_no, [l1, l2, p1, p2]) in biaxial_rows(table, BIAXIAL_HEADER)? {
        let state = BiaxialState {
            stretch1: l1,
            stretch2: l2,
            nominal_stress1_mpa: p1,
            nominal_stress2_mpa: p2,
        };
        state
            .check()
            .map_err(|m| table.error(format!("line {line_no}: {m}")))?;
        if state.stretch1 == 1.0 && state.stretch2 == 1.0 {
            continue;
        }
        states.push(state);
    }
    if states.len() < MIN_POINTS_PER_CURVE {
        return Err(table.error(format!(
            "too few states: {} deformed, expected at least {MIN_POINTS_PER_CURVE}",
            states.len()
        )));
    }
    Ok(states)
}

impl fmt::Display for LoadCase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Cauchy stress in MPa from a force in N and the current section in mm² (N/mm² = MPa).
pub fn cauchy_stress_mpa(force_n: f64, current_section_mm2: f64) -> f64 {
    assert!(
        current_section_mm2 > 0.0,
        "current section must be positive, got {current_section_mm2}"
    );
    force_n / current_section_mm2
}

/// Nominal stress in MPa from a force in N and the reference (undeformed) section in mm².
pub fn nominal_stress_mpa(force_n: f64, reference_section_mm2: f64) -> f64 {
    assert!(
        reference_section_mm2 > 0.0,
        "reference section must be positive, got {reference_section_mm2}"
    );
    force_n / reference_section_mm2
}

/// Current section (mm²) normal to the loaded direction 1 of a specimen of reference width
/// `width0_mm` (along 2) and thickness `thickness0_mm` (along 3): w0 λ2 · t0 λ3 = A0 / λ1.
pub fn current_section_mm2(
    case: LoadCase,
    stretch: f64,
    width0_mm: f64,
    thickness0_mm: f64,
) -> f64 {
    let [_, l2, l3] = case.stretches(stretch);
    width0_mm * l2 * thickness0_mm * l3
}

/// One measured load path: loaded stretch and nominal stress along it.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub case: LoadCase,
    /// Strictly increasing, every value > 1.
    pub stretch: Vec<f64>,
    pub nominal_stress_mpa: Vec<f64>,
    /// Rows at stretch exactly 1.0 that were dropped (see the module doc).
    pub reference_rows_dropped: usize,
}

impl Curve {
    /// Builds a curve, checking the same rules as the CSV reader (without line numbers).
    pub fn new(
        case: LoadCase,
        stretch: Vec<f64>,
        nominal_stress_mpa: Vec<f64>,
    ) -> Result<Self, DataError> {
        let source = format!("{case} data");
        let rows: Vec<(usize, f64, f64)> = stretch
            .iter()
            .zip(&nominal_stress_mpa)
            .enumerate()
            .map(|(i, (&l, &p))| (i + 1, l, p))
            .collect();
        if stretch.len() != nominal_stress_mpa.len() {
            return Err(DataError::new(
                &source,
                format!(
                    "{} stretches but {} stresses",
                    stretch.len(),
                    nominal_stress_mpa.len()
                ),
            ));
        }
        build_curve(case, &source, &rows, "row")
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.stretch.len()
    }

    pub fn is_empty(&self) -> bool {
        self.stretch.is_empty()
    }

    /// Cauchy stresses σ = λ P, MPa.
    pub fn cauchy_stress_mpa(&self) -> Vec<f64> {
        self.stretch
            .iter()
            .zip(&self.nominal_stress_mpa)
            .map(|(l, p)| l * p)
            .collect()
    }
}

/// Minimum number of points a curve must hold after dropping the reference rows.
pub const MIN_POINTS_PER_CURVE: usize = 2;

/// A data error naming its source and what was expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{source_name}: {message}")]
pub struct DataError {
    pub source_name: String,
    pub message: String,
}

impl DataError {
    pub(crate) fn new(source_name: &str, message: String) -> Self {
        DataError {
            source_name: source_name.to_string(),
            message,
        }
    }
}

/// Reads a load case's CSV: `stretch,nominal_stress_mpa`, or a machine's export
/// ([`crate::table`]: title lines, units row, `;` and decimal commas; [`crate::columns`]: which
/// columns, in which units).
pub fn read_curve_csv(
    path: &Path,
    case: LoadCase,
    options: &ReadOptions,
) -> Result<Curve, DataError> {
    curve_of(&Table::read(path, options.table)?, case, options.specimen)
}

/// Parses CSV text as [`read_curve_csv`]; `source_name` is used in error messages.
pub fn parse_curve_csv(
    text: &str,
    source_name: &str,
    case: LoadCase,
    options: &ReadOptions,
) -> Result<Curve, DataError> {
    curve_of(
        &Table::parse(text, source_name, options.table)?,
        case,
        options.specimen,
    )
}

fn curve_of(table: &Table, case: LoadCase, specimen: Specimen) -> Result<Curve, DataError> {
    let rows = curve_rows(table, specimen)?;
    if rows.is_empty() {
        return Err(table.error("no data rows after the header".into()));
    }
    build_curve(case, &table.source, &rows, "line")
}

fn build_curve(
    case: LoadCase,
    source: &str,
    rows: &[(usize, f64, f64)],
    unit: &str,
) -> Result<Curve, DataError> {
    let mut curve = Curve {
        case,
        stretch: Vec::new(),
        nominal_stress_mpa: Vec::new(),
        reference_rows_dropped: 0,
    };
    let mut previous: Option<f64> = None;
    for &(no, stretch, stress) in rows {
        if !stretch.is_finite() || !stress.is_finite() {
            return Err(DataError::new(
                source,
                format!("{unit} {no}: values must be finite numbers"),
            ));
        }
        if stretch < 1.0 {
            return Err(DataError::new(
                source,
                format!(
                "{unit} {no}: stretch {stretch} is below 1; expected tension data (stretch >= 1)"
            ),
            ));
        }
        if let Some(prev) = previous {
            if stretch <= prev {
                return Err(DataError::new(source, format!(
                    "{unit} {no}: stretch {stretch} does not increase (previous {prev}); expected strictly increasing stretches"
                )));
            }
        }
        previous = Some(stretch);
        if stretch == 1.0 {
            curve.reference_rows_dropped += 1;
            continue;
        }
        curve.stretch.push(stretch);
        curve.nominal_stress_mpa.push(stress);
    }
    if curve.len() < MIN_POINTS_PER_CURVE {
        return Err(DataError::new(
            source,
            format!(
                "too few points: {} with stretch > 1, expected at least {MIN_POINTS_PER_CURVE}",
                curve.len()
            ),
        ));
    }
    Ok(curve)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariants_of_the_three_cases() {
        let (i1, i2) = LoadCase::Uniaxial.invariants(2.0);
        assert!((i1 - 5.0).abs() < 1e-12 && (i2 - 4.25).abs() < 1e-12);
        let (i1, i2) = LoadCase::Equibiaxial.invariants(2.0);
        assert!((i1 - 8.0625).abs() < 1e-12 && (i2 - 16.5).abs() < 1e-12);
        let (i1, i2) = LoadCase::PureShear.invariants(2.0);
        assert!((i1 - i2).abs() < 1e-12, "pure shear has I1 = I2");
    }

    #[test]
    fn biaxial_csv_reads_and_refuses_bad_rows_naming_the_line() {
        let good = format!("{BIAXIAL_HEADER}\n1,1,0,0\n1.2,1.1,0.3,0.2\n\n1.4,1.2,0.5,0.3\n");
        let states = parse_biaxial_csv(&good, "g.csv", &ReadOptions::default()).unwrap();
        assert_eq!(states.len(), 2, "the undeformed row is dropped");
        assert_eq!(states[1].nominal_stress2_mpa, 0.3);
        let bad = |text: &str, needle: &str| {
            let e = parse_biaxial_csv(text, "b.csv", &ReadOptions::default())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("b.csv: ") && e.contains(needle), "{e}");
        };
        bad("", "empty file");
        bad(
            "1.2,1.1,0.3,0.2\n1.3,1.1,0.3,0.2\n",
            "line 1: expected a header",
        );
        bad(
            "lambda1,lambda2,p1,p2\n1.2,1.1,0.3,0.2\n",
            "line 1: expected the header",
        );
        let h = BIAXIAL_HEADER;
        bad(
            &format!("{h}\n1.2,1.1,0.3,0.2\n1.3,1.1,0.4\n"),
            "line 3: expected 4 cells as the header on line 1",
        );
        bad(
            &format!("{h}\n1.2,1.1,0.3,0.2\n1.3,x,0.4,0.1\n"),
            "line 3, column 2 `lambda2`: `x` is not a finite number",
        );
        bad(
            &format!("{h}\n1.2,1.1,NaN,0.2\n1.3,1.1,0.4,0.1\n"),
            "line 2, column 3 `nominal_stress1_mpa`: `NaN` is not a finite",
        );
        bad(
            &format!("{h}\n1.2,1.1,0.3,inf\n1.3,1.1,0.4,0.1\n"),
            "line 2, column 4 `nominal_stress2_mpa`: `inf` is not a finite",
        );
        bad(
            &format!("{h}\n1.2,-1.1,0.3,0.2\n1.3,1.1,0.4,0.1\n"),
            "line 2: lambda2 -1.1 must be > 0",
        );
        bad(&format!("{h}\n1.2,1.1,0.3,0.2\n"), "too few states: 1");
    }

    #[test]
    fn canonical_cases_are_path_ratios() {
        for case in LoadCase::ALL {
            let (l1, l2) = case.in_plane_stretches(1.7);
            let state = BiaxialState {
                stretch1: l1,
                stretch2: l2,
                nominal_stress1_mpa: 0.0,
                nominal_stress2_mpa: 0.0,
            };
            let rho = state.path_ratio().unwrap();
            assert_eq!(LoadCase::of_path_ratio(rho, 0.01), Some(case));
        }
        assert_eq!(LoadCase::of_path_ratio(0.5, 0.15), None);
    }

    #[test]
    fn canonical_curves_of_states_leave_the_general_ones_out() {
        let state = |l1: f64, l2: f64| BiaxialState {
            stretch1: l1,
            stretch2: l2,
            nominal_stress1_mpa: l1 - 1.0,
            nominal_stress2_mpa: l2 - 1.0,
        };
        let mut states = Vec::new();
        for k in 1..=5 {
            let l = 1.0 + 0.1 * k as f64;
            states.push(state(1.0 / l.sqrt(), l)); // uniaxial along y
            states.push(state(l, l)); // equibiaxial
            states.push(state(l, l.sqrt())); // ρ = 0.5
        }
        let curves = canonical_curves(&states, 0.15);
        assert_eq!(curves.len(), 2);
        assert_eq!(curves[0].case, LoadCase::Uniaxial);
        assert_eq!(curves[0].len(), 5);
        assert!(
            (curves[0].stretch[4] - 1.5).abs() < 1e-12,
            "loaded stretch: the larger"
        );
        assert!((curves[0].nominal_stress_mpa[4] - 0.5).abs() < 1e-12);
        assert_eq!(curves[1].case, LoadCase::Equibiaxial);
        assert_eq!(curves[1].len(), 5);
    }

    #[test]
    fn section_and_stresses_agree() {
        let a = current_section_mm2(LoadCase::Uniaxial, 2.0, 10.0, 2.0);
        assert!((a - 10.0).abs() < 1e-12);
        let force_n = 50.0;
        assert!(
            (cauchy_stress_mpa(force_n, a) - 2.0 * nominal_stress_mpa(force_n, 20.0)).abs() < 1e-12
        );
    }
}
