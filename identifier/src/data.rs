//! Load cases, their kinematics, and the `stretch,nominal_stress_mpa` CSV reader.
//!
//! Every load case is a homogeneous incompressible plane-stress state: the loaded stretch λ
//! along direction 1, the traction-free thickness along direction 3 (σ3 = 0).
//!
//! Stretch exactly 1.0 is the undeformed reference: both sides of eq. 19 vanish there, so it
//! carries no information on W (and would divide by zero in eqs 20, 23 and in relative
//! residuals). The reader accepts it and drops it, counting it in
//! [`Curve::reference_rows_dropped`]. Any stretch below 1.0 is an error (tension data only).

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
    fn new(source_name: &str, message: String) -> Self {
        DataError {
            source_name: source_name.to_string(),
            message,
        }
    }
}

/// Reads a `stretch,nominal_stress_mpa` CSV (one header line, then two numeric columns).
pub fn read_curve_csv(path: &Path, case: LoadCase) -> Result<Curve, DataError> {
    let source = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| DataError::new(&source, format!("cannot read the file: {e}")))?;
    parse_curve_csv(&text, &source, case)
}

/// Parses CSV text; `source_name` is used in error messages.
pub fn parse_curve_csv(text: &str, source_name: &str, case: LoadCase) -> Result<Curve, DataError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(DataError::new(
            source_name,
            "empty file: expected a header `stretch,nominal_stress_mpa` then data rows".into(),
        ));
    };
    let header_first = header.split(',').next().unwrap_or("").trim();
    if header_first.parse::<f64>().is_ok() {
        return Err(DataError::new(
            source_name,
            "line 1: expected a header `stretch,nominal_stress_mpa`, found numbers".into(),
        ));
    }
    let mut rows = Vec::new();
    for (index, line) in lines {
        let line_no = index + 1;
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != 2 {
            return Err(DataError::new(source_name, format!(
                "line {line_no}: expected 2 cells `stretch,nominal_stress_mpa`, found {} in `{line}`", cells.len()
            )));
        }
        let parse = |cell: &str, what: &str| -> Result<f64, DataError> {
            match cell.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(DataError::new(
                    source_name,
                    format!("line {line_no}: {what} `{cell}` is not a finite number"),
                )),
            }
        };
        rows.push((
            line_no,
            parse(cells[0], "stretch")?,
            parse(cells[1], "nominal stress")?,
        ));
    }
    if rows.is_empty() {
        return Err(DataError::new(
            source_name,
            "no data rows after the header".into(),
        ));
    }
    build_curve(case, source_name, &rows, "line")
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
    fn section_and_stresses_agree() {
        let a = current_section_mm2(LoadCase::Uniaxial, 2.0, 10.0, 2.0);
        assert!((a - 10.0).abs() < 1e-12);
        let force_n = 50.0;
        assert!(
            (cauchy_stress_mpa(force_n, a) - 2.0 * nominal_stress_mpa(force_n, 20.0)).abs() < 1e-12
        );
    }
}
