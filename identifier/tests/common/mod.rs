//! Shared by the integration tests: Treloar's (1944) three load cases from `../shared`.

use identifier::data::{read_curve_csv, Curve, LoadCase};
use std::path::Path;

pub const DATA_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/treloar1944");

/// Uniaxial, equibiaxial and pure-shear curves, or `None` (said on stderr) without the data.
pub fn treloar() -> Option<Vec<Curve>> {
    let dir = Path::new(DATA_DIR);
    if !dir.exists() {
        eprintln!("SKIPPED: Treloar data not found at {DATA_DIR}");
        return None;
    }
    let files = [
        ("uniaxial.csv", LoadCase::Uniaxial),
        ("equibiaxial.csv", LoadCase::Equibiaxial),
        ("pure_shear.csv", LoadCase::PureShear),
    ];
    Some(
        files
            .iter()
            .map(|(f, c)| read_curve_csv(&dir.join(f), *c).expect("Treloar CSV reads"))
            .collect(),
    )
}
