//! Which columns of a [`Table`] give the identifier's data, and in which units, converted to
//! the identifier's (stretch, MPa = N/mm²).
//!
//! General biaxial states: the columns `lambda1`, `lambda2`, `nominal_stress1`,
//! `nominal_stress2` (any stress unit, as below; other columns ignored).
//!
//! A load case's curve:
//! The stretch is a column named `stretch` or `lambda…`; else a strain (`…strain…`, unit `%`
//! or `-`, `mm/mm`: λ = 1 + e); else an extension (`…extension…`, `…displacement…`,
//! `…elongation…`, unit mm, µm or m: λ = 1 + Δl / L0 with the gauge length L0). The nominal
//! stress is a column named `…stress…` (unit MPa, N/mm², kPa, Pa, GPa); else a force
//! (`…force…`, `…load…`, unit N or kN: P = F / A0 with the reference section A0). Names are
//! matched without case; a unit comes from the header (`Load (kN)`), the units row, or a
//! name's last `_unit` (`nominal_stress_mpa`). A file of exactly two columns named otherwise is
//! the identifier's own format: stretch, then nominal stress in MPa.

use crate::data::DataError;
use crate::table::{Column, Table};
use wire::names::Named;
use wire::units::{ForceUnit, LengthUnit, StressUnit};

/// What a machine's file lacks to give stretches and nominal stresses: the specimen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Specimen {
    /// Gauge length L0 (mm): turns an extension column into stretches.
    pub gauge_length_mm: Option<f64>,
    /// Reference (undeformed) section A0 (mm²): turns a force column into nominal stresses.
    pub section_mm2: Option<f64>,
}

/// Where the stretch comes from and how.
#[derive(Clone, Copy, Debug, PartialEq)]
enum StretchFrom {
    Stretch(usize),
    /// λ = 1 + factor · cell.
    Strain(usize, f64),
    /// λ = 1 + cell · factor_mm / L0.
    Extension(usize, f64, f64),
}

/// Where the nominal stress comes from and how: P = cell · factor (MPa).
#[derive(Clone, Copy, Debug, PartialEq)]
struct StressFrom {
    column: usize,
    factor_mpa: f64,
}

/// Each data row of `table` as (line, stretch, nominal stress MPa).
pub fn curve_rows(table: &Table, specimen: Specimen) -> Result<Vec<(usize, f64, f64)>, DataError> {
    let (stretch, stress) = match (
        stretch_from(table, specimen)?,
        stress_from(table, specimen)?,
    ) {
        (Some(l), Some(p)) => (l, p),
        (None, None) if table.columns.len() == 2 => (
            StretchFrom::Stretch(0),
            StressFrom {
                column: 1,
                factor_mpa: 1.0,
            },
        ),
        (l, _) => {
            let what = match l {
                None => "stretch: a column named `stretch` or `lambda`, a strain (`Strain (%)`), or an extension (`Extension (mm)`, with --gauge-length-mm)",
                Some(_) => "nominal stress: a column named `…stress…` (`Stress (MPa)`), or a force (`Load (kN)`, with --section-mm2)",
            };
            return Err(table.error(format!(
                "line {}: no column gives the {what}; the header has {}",
                table.header_line,
                names(&table.columns)
            )));
        }
    };
    table
        .rows
        .iter()
        .map(|row| {
            let lambda = match stretch {
                StretchFrom::Stretch(c) => table.number(row, c)?,
                StretchFrom::Strain(c, f) => 1.0 + f * table.number(row, c)?,
                StretchFrom::Extension(c, f, l0) => 1.0 + table.number(row, c)? * f / l0,
            };
            let p = table.number(row, stress.column)? * stress.factor_mpa;
            Ok((row.line, lambda, p))
        })
        .collect()
}

/// The names of a general biaxial file's columns, a stress unit after the stresses.
const BIAXIAL_COLUMNS: [&str; 4] = ["lambda1", "lambda2", "nominal_stress1", "nominal_stress2"];

/// Each data row of `table` as (line, [λ1, λ2, P1 MPa, P2 MPa]); `header` is the header the
/// identifier writes, for the error.
pub fn biaxial_rows(table: &Table, header: &str) -> Result<Vec<(usize, [f64; 4])>, DataError> {
    let mut at = [(0, 1.0); 4];
    for (k, name) in BIAXIAL_COLUMNS.iter().enumerate() {
        let found = table.find(|n| match k {
            0 | 1 => n == *name,
            _ => n == *name || n.strip_prefix(name).is_some_and(|r| r.starts_with('_')),
        })?;
        let Some(c) = found else {
            return Err(table.error(format!(
                "line {}: expected the header `{header}` (or a stress unit in the header or a units row), found {}",
                table.header_line,
                names(&table.columns)
            )));
        };
        at[k] = match k {
            0 | 1 => (c, 1.0),
            _ => (c, named_unit::<StressUnit>(table, c, "a stress")?.to_mpa()),
        };
    }
    table
        .rows
        .iter()
        .map(|row| {
            let mut values = [0.0; 4];
            for (v, &(c, f)) in values.iter_mut().zip(&at) {
                *v = table.number(row, c)? * f;
            }
            Ok((row.line, values))
        })
        .collect()
}

fn stretch_from(table: &Table, specimen: Specimen) -> Result<Option<StretchFrom>, DataError> {
    if let Some(c) =
        table.find(|n| n.starts_with("stretch") || n.starts_with("lambda") || n == "λ")?
    {
        return match unit(&table.columns[c], &["-", "1", "mm/mm"]).as_deref() {
            None | Some("-" | "1" | "mm/mm") => Ok(Some(StretchFrom::Stretch(c))),
            _ => Err(unit_error(table, c, "a stretch", "none, `-` or `mm/mm`")),
        };
    }
    if let Some(c) = table.find(|n| n.contains("strain"))? {
        let column = &table.columns[c];
        return match unit(column, &["%", "-", "1", "mm/mm"]).as_deref() {
            Some("%") => Ok(Some(StretchFrom::Strain(c, 0.01))),
            Some("-" | "1" | "mm/mm") => Ok(Some(StretchFrom::Strain(c, 1.0))),
            _ => Err(unit_error(table, c, "a strain", "`%`, `-` or `mm/mm`")),
        };
    }
    let extension = table.find(|n| {
        n.contains("extension") || n.contains("displacement") || n.contains("elongation")
    })?;
    if let Some(c) = extension {
        let factor = named_unit::<LengthUnit>(table, c, "an extension")?.to_mm();
        let l0 = given(
            table,
            c,
            specimen.gauge_length_mm,
            "an extension",
            "the gauge length with --gauge-length-mm",
        )?;
        return Ok(Some(StretchFrom::Extension(c, factor, l0)));
    }
    Ok(None)
}

fn stress_from(table: &Table, specimen: Specimen) -> Result<Option<StressFrom>, DataError> {
    if let Some(c) = table.find(|n| n.contains("stress"))? {
        let factor_mpa = named_unit::<StressUnit>(table, c, "a stress")?.to_mpa();
        return Ok(Some(StressFrom {
            column: c,
            factor_mpa,
        }));
    }
    if let Some(c) = table.find(|n| n.contains("force") || n.contains("load"))? {
        let factor_n = named_unit::<ForceUnit>(table, c, "a force")?.to_n();
        let a0 = given(
            table,
            c,
            specimen.section_mm2,
            "a force",
            "the reference section with --section-mm2",
        )?;
        return Ok(Some(StressFrom {
            column: c,
            factor_mpa: factor_n / a0,
        }));
    }
    Ok(None)
}

/// The specimen's `value` column `c` needs, or an error saying what to give.
fn given(
    table: &Table,
    c: usize,
    value: Option<f64>,
    what: &str,
    give: &str,
) -> Result<f64, DataError> {
    value.ok_or_else(|| {
        table.error(format!(
            "column {} `{}` is {what}: give {give}",
            c + 1,
            table.columns[c].name
        ))
    })
}

/// The unit of a column: stated, or its name's last `_unit` when that is one of `known`.
fn unit(column: &Column, known: &[&str]) -> Option<String> {
    column.unit.clone().or_else(|| {
        let (_, suffix) = column.name.rsplit_once('_')?;
        known
            .iter()
            .find(|k| k.eq_ignore_ascii_case(suffix))
            .map(|k| k.to_string())
    })
}

/// A column's unit as one of `U`'s names, from the header, the units row or the name.
fn named_unit<U: Named>(table: &Table, c: usize, what: &str) -> Result<U, DataError> {
    let names: Vec<&str> = U::ALL
        .iter()
        .flat_map(|u| std::iter::once(u.name()).chain(u.aliases().iter().copied()))
        .collect();
    let stated = unit(&table.columns[c], &names);
    match stated.as_deref().map(U::parse_name) {
        Some(Ok(u)) => Ok(u),
        _ => Err(unit_error(table, c, what, &U::expected())),
    }
}

fn unit_error(table: &Table, c: usize, what: &str, expected: &str) -> DataError {
    let column = &table.columns[c];
    let found = match &column.unit {
        Some(u) => format!("`{u}`"),
        None => "stated nowhere".to_string(),
    };
    table.error(format!(
        "column {} `{}` is {what}; its unit is {found}: expected {expected} (in the header, `{} (UNIT)`, or a units row under it)",
        c + 1,
        column.name,
        column.name
    ))
}

fn names(columns: &[Column]) -> String {
    columns
        .iter()
        .map(|c| format!("`{}`", c.name))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::TableOptions;

    fn rows(text: &str, specimen: Specimen) -> Result<Vec<(usize, f64, f64)>, String> {
        let table =
            Table::parse(text, "m.csv", TableOptions::default()).map_err(|e| e.to_string())?;
        curve_rows(&table, specimen).map_err(|e| e.to_string())
    }

    #[test]
    fn force_and_extension_in_any_unit_give_stretch_and_megapascals() {
        let specimen = Specimen {
            gauge_length_mm: Some(50.0),
            section_mm2: Some(20.0),
        };
        let text = "Time;Extension;Load\n(s);(m);(kN)\n1,0;0,005;0,04\n";
        let got = rows(text, specimen).unwrap();
        assert_eq!(got.len(), 1);
        let (line, lambda, p) = got[0];
        assert_eq!(line, 3);
        assert!(
            (lambda - 1.1).abs() < 1e-12 && (p - 2.0).abs() < 1e-12,
            "{got:?}"
        );
        let got = rows("Strain (%);Stress [kPa]\n10;500\n", specimen).unwrap();
        assert!((got[0].1 - 1.1).abs() < 1e-12 && (got[0].2 - 0.5).abs() < 1e-12);
        let got = rows("stretch,nominal_stress_mpa\n1.1,0.5\n", Specimen::default()).unwrap();
        assert_eq!(got, [(2, 1.1, 0.5)]);
        // The identifier's own two columns, named otherwise.
        assert_eq!(
            rows("l,p\n1.1,0.5\n", Specimen::default()).unwrap(),
            [(2, 1.1, 0.5)]
        );
    }

    #[test]
    fn what_a_file_lacks_is_named() {
        let none = Specimen::default();
        let e = rows("Time;Extension (mm);Load (kN)\n1;2;3\n", none).unwrap_err();
        assert!(e.contains("column 2 `Extension` is an extension: give the gauge length with --gauge-length-mm"), "{e}");
        let e = rows("Time;Strain;Stress (MPa)\n1;2;3\n", none).unwrap_err();
        assert!(
            e.contains("column 2 `Strain` is a strain; its unit is stated nowhere"),
            "{e}"
        );
        let e = rows("Strain (%);Load (lbf)\n1;2\n", none).unwrap_err();
        assert!(
            e.contains("column 2 `Load` is a force; its unit is `lbf`: expected"),
            "{e}"
        );
        let e = rows("Time;Stretch;Temperature\n1;2;3\n", none).unwrap_err();
        assert!(
            e.contains("line 1: no column gives the nominal stress"),
            "{e}"
        );
    }
}
