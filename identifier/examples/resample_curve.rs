//! Resamples a `stretch,nominal_stress_mpa` curve to many points (for timing `identify` on
//! large inputs): linear interpolation between the measured points on an even stretch grid,
//! plus a deterministic relative noise on the stress.
//!
//! `cargo run --release -p identifier --example resample_curve -- IN.csv OUT.csv POINTS [NOISE_FRACTION] [SEED]`

use identifier::data::{read_curve_csv, LoadCase};
use std::fmt::Write as _;
use std::path::Path;

/// splitmix64: a tiny deterministic generator, uniform in [−1, 1).
fn next_symmetric_unit(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: resample_curve IN.csv OUT.csv POINTS [NOISE_FRACTION] [SEED]".into());
    }
    let points: usize = args[2].parse()?;
    let noise_fraction: f64 = args.get(3).map_or(Ok(0.01), |s| s.parse())?;
    let mut seed: u64 = args.get(4).map_or(Ok(1), |s| s.parse())?;
    if points < 2 {
        return Err("POINTS must be at least 2".into());
    }
    // The load case only matters for the reader's checks, which are the same for all three.
    let curve = read_curve_csv(Path::new(&args[0]), LoadCase::Uniaxial, &Default::default())?;
    let (first, last) = (curve.stretch[0], curve.stretch[curve.len() - 1]);
    let mut text = String::from("stretch,nominal_stress_mpa\n");
    let mut segment = 0;
    for k in 0..points {
        let stretch = first + (last - first) * k as f64 / (points - 1) as f64;
        while segment + 2 < curve.len() && curve.stretch[segment + 1] < stretch {
            segment += 1;
        }
        let (l0, l1) = (curve.stretch[segment], curve.stretch[segment + 1]);
        let (p0, p1) = (
            curve.nominal_stress_mpa[segment],
            curve.nominal_stress_mpa[segment + 1],
        );
        let stress = p0 + (p1 - p0) * (stretch - l0) / (l1 - l0);
        let noisy = stress * (1.0 + noise_fraction * next_symmetric_unit(&mut seed));
        writeln!(text, "{stretch:.9},{noisy:.9}")?;
    }
    std::fs::write(&args[1], text)?;
    Ok(())
}
