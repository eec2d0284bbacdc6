//! The cell delimiter of a machine's CSV log, as a user names it (`,`, `;` or `tab`).

/// What separates the cells of a row.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Delimiter {
    #[default]
    Comma,
    /// With a semicolon, a decimal comma is read too (`4,5` = 4.5).
    Semicolon,
    /// With a tab, a decimal comma is read too.
    Tab,
}

wire::named!(Delimiter, "delimiter", { Comma => ",", Semicolon => ";", Tab => "tab" | "\t" });

impl Delimiter {
    pub fn as_char(self) -> char {
        match self {
            Delimiter::Comma => ',',
            Delimiter::Semicolon => ';',
            Delimiter::Tab => '\t',
        }
    }
}
