//! The cell delimiter of a machine's CSV log, as a user names it (`,`, `;` or `tab`).

/// What separates the cells of a row. With any of them a comma inside a cell is a decimal
/// comma (`4,5` = 4.5; with a comma as delimiter such a cell is quoted, `"4,5"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Delimiter {
    #[default]
    Comma,
    Semicolon,
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
