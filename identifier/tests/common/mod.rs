//! Shared by the integration tests: Treloar's (1944) three load cases from `testdata/`.

use identifier::data::{read_curve_csv, Curve, LoadCase};

/// Uniaxial, equibiaxial and pure-shear curves, or `None` without the data (skipped with a
/// message; a failure under `DICSTREAM_REQUIRE_SHARED=1`, see `testkit::shared_data`).
pub fn treloar() -> Option<Vec<Curve>> {
    let dir = testkit::shared_data("treloar1944")?;
    let files = [
        ("uniaxial.csv", LoadCase::Uniaxial),
        ("equibiaxial.csv", LoadCase::Equibiaxial),
        ("pure_shear.csv", LoadCase::PureShear),
    ];
    Some(
        files
            .iter()
            .map(|(f, c)| {
                read_curve_csv(&dir.join(f), *c, &Default::default()).expect("Treloar CSV reads")
            })
            .collect(),
    )
}
