//! Delimited text as test machines write it, the one place both readers of it share (the rig's
//! follower of a machine's CSV log, `rig::csv_follow`, and the identifier's data files,
//! `identifier::table`): the cell delimiter a user names or that a row shows, numbers with a
//! decimal comma, and a header cell's unit (`Force (kN)`, `Force [kN]`).

/// What separates the cells of a row. With any of them a comma inside a cell is a decimal
/// comma (`4,5` = 4.5; with a comma as delimiter such a cell is quoted, `"4,5"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Delimiter {
    #[default]
    Comma,
    Semicolon,
    Tab,
}

crate::named!(Delimiter, "delimiter", { Comma => ",", Semicolon => ";", Tab => "tab" | "\t" });

impl Delimiter {
    pub fn as_char(self) -> char {
        match self {
            Delimiter::Comma => ',',
            Delimiter::Semicolon => ';',
            Delimiter::Tab => '\t',
        }
    }

    /// The delimiter of a data row: a tab if the row has one, else `;` if it has one, else
    /// `,`. In that order because a `;` or tab delimited row may hold decimal commas, while
    /// a comma delimited row quotes its decimal commas and holds no `;` outside quotes.
    pub fn of_row(row: &str) -> Delimiter {
        let unquoted: String = row.split('"').step_by(2).collect();
        if unquoted.contains('\t') {
            Delimiter::Tab
        } else if unquoted.contains(';') {
            Delimiter::Semicolon
        } else {
            Delimiter::Comma
        }
    }
}

/// A cell as a finite number, a decimal comma read as a point (`4,5` = 4.5; `1,234.5`, with
/// both, is no number); white space around it ignored.
pub fn parse_decimal(cell: &str) -> Option<f64> {
    written_number(cell).filter(|v| v.is_finite())
}

/// A cell written as a number, finite or not (`NaN`, `inf`): what tells a row of numbers
/// from a header or a units row.
pub fn written_number(cell: &str) -> Option<f64> {
    cell.trim().replace(',', ".").parse::<f64>().ok()
}

/// A header cell as (name, unit): `Fx (kN)`, `Fx [kN]` or `Fx` (quotes are the record
/// reader's).
pub fn split_unit(cell: &str) -> (String, Option<String>) {
    let cell = cell.trim();
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let Some(stripped) = cell.strip_suffix(close) {
            if let Some(at) = stripped.rfind(open) {
                return (
                    stripped[..at].trim().to_string(),
                    Some(stripped[at + 1..].trim().to_string()),
                );
            }
        }
    }
    (cell.to_string(), None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_cells_give_name_and_unit() {
        assert_eq!(split_unit(" Fx (kN) "), ("Fx".into(), Some("kN".into())));
        assert_eq!(split_unit("Time [s]"), ("Time".into(), Some("s".into())));
        assert_eq!(split_unit("Fx"), ("Fx".into(), None));
    }

    #[test]
    fn decimal_commas_are_points_and_both_separators_are_no_number() {
        assert_eq!(parse_decimal(" 2,25"), Some(2.25));
        assert_eq!(parse_decimal("1.5e3"), Some(1500.0));
        assert_eq!(parse_decimal("1,234.5"), None);
        assert_eq!(parse_decimal("inf"), None);
        assert!(written_number("NaN").is_some_and(f64::is_nan));
        assert_eq!(parse_decimal("N"), None);
    }

    #[test]
    fn a_rows_delimiter_is_tab_then_semicolon_then_comma_outside_quotes() {
        assert_eq!(Delimiter::of_row("1\t2,5"), Delimiter::Tab);
        assert_eq!(Delimiter::of_row("1,5;2,5"), Delimiter::Semicolon);
        assert_eq!(Delimiter::of_row("1.5,\"2;5\""), Delimiter::Comma);
        assert_eq!(Delimiter::of_row("1.5,2.5"), Delimiter::Comma);
    }
}
