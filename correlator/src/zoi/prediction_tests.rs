//! The predicted path of [`ZoiEngine::correlate`]: from a prediction within a pixel it finds
//! what the full integer search finds, and from a prediction several pixels off it falls back
//! to that search.

use super::*;

const SIZE: usize = 128;
const N: usize = 32;
const TOP_LEFT: (usize, usize) = (48, 48);

/// Gaussian speckles (radius about 2 px) at pseudo-random places, moved by `shift_px`:
/// an exact sub-pixel translation of one pattern.
fn speckle(shift_px: (f64, f64)) -> Vec<u16> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let spots: Vec<(f64, f64, f64)> = (0..1400)
        .map(|_| (next() * SIZE as f64, next() * SIZE as f64, 0.5 + next()))
        .collect();
    let mut pixels = vec![0u16; SIZE * SIZE];
    for (i, p) in pixels.iter_mut().enumerate() {
        let (x, y) = (
            (i % SIZE) as f64 - shift_px.0,
            (i / SIZE) as f64 - shift_px.1,
        );
        let mut value = 2000.0;
        for &(sx, sy, a) in &spots {
            let d2 = (x - sx).powi(2) + (y - sy).powi(2);
            if d2 < 40.0 {
                value += 9000.0 * a * (-d2 / (2.0 * 2.0 * 2.0)).exp();
            }
        }
        *p = value.min(65535.0) as u16;
    }
    pixels
}

fn image(pixels: &[u16]) -> Image<'_> {
    Image {
        pixels,
        width_px: SIZE,
        height_px: SIZE,
    }
}

/// The node's correlation of `deformed` from `guess_px`, predicted or not.
fn correlate(
    reference: &[u16],
    deformed: &[u16],
    guess_px: (f64, f64),
    predicted: bool,
) -> ZoiResult {
    let mut engine = ZoiEngine::new(N);
    let mut plain = vec![Complex32::new(0.0, 0.0); spectrum_len(N)];
    let mut windowed = vec![0.0; N * N];
    let mut sensitivity = GradientSensitivity::default();
    assert!(engine.prepare_reference(
        image(reference),
        TOP_LEFT.0,
        TOP_LEFT.1,
        &mut plain,
        &mut windowed,
        &mut sensitivity
    ));
    let spectra = ReferenceSpectra {
        plain: &plain,
        windowed: &windowed,
    };
    let search = ZoiSearch {
        top_left_px: TOP_LEFT,
        guess_px,
        warp: None,
        iterations: SubpixelIterations::paper(10),
        predicted,
    };
    engine.correlate(&spectra, image(deformed), search)
}

/// A prediction as close as a live frame's (the last value plus the last step, off by the
/// noise and the change of speed: hundredths of a pixel) finds the full search's displacement
/// to within 1e-3 px; one off by up to half a pixel is as close to the truth as the full
/// search, whose own iterations start up to half a pixel from the peak too.
#[test]
fn a_prediction_within_a_pixel_finds_what_the_full_search_finds() {
    let reference = speckle((0.0, 0.0));
    for shift in [(0.37, -0.21), (2.62, 1.45), (-1.5, 0.08)] {
        let deformed = speckle(shift);
        let full = correlate(&reference, &deformed, (0.0, 0.0), false);
        assert_eq!(full.status, NodeStatus::Ok);
        let full_error = (full.u_px - shift.0).abs().max((full.v_px - shift.1).abs());
        for error in [
            (0.0, 0.0),
            (0.03, -0.02),
            (-0.05, 0.04),
            (0.3, -0.2),
            (-0.45, 0.4),
        ] {
            let guess = (shift.0 + error.0, shift.1 + error.1);
            let predicted = correlate(&reference, &deformed, guess, true);
            assert_eq!(predicted.status, NodeStatus::Ok, "{shift:?} {error:?}");
            let apart = (predicted.u_px - full.u_px)
                .abs()
                .max((predicted.v_px - full.v_px).abs());
            let own_error = (predicted.u_px - shift.0)
                .abs()
                .max((predicted.v_px - shift.1).abs());
            eprintln!("{shift:?} {error:?}: apart {apart:.5} error {own_error:.5} (full {full_error:.5}), iterations {} against {}", predicted.iterations, full.iterations);
            if error.0.abs().max(error.1.abs()) <= 0.05 {
                assert!(
                    apart < 1e-3,
                    "{shift:?} from {guess:?}: {predicted:?} against {full:?}"
                );
            } else {
                assert!(own_error < 3e-3, "{shift:?} from {guess:?}: {predicted:?}");
            }
            // The shortcut skips the search's first, unshifted iteration at least.
            assert!(
                predicted.iterations <= full.iterations,
                "{predicted:?} {full:?}"
            );
        }
    }
}

#[test]
fn a_prediction_several_pixels_off_falls_back_to_the_full_search() {
    let reference = speckle((0.0, 0.0));
    let shift = (0.37, -0.21);
    let deformed = speckle(shift);
    for error in [(4.0, 0.0), (-3.0, 5.0), (6.0, -6.0), (1.0, 1.0)] {
        let guess = (shift.0 + error.0, shift.1 + error.1);
        let predicted = correlate(&reference, &deformed, guess, true);
        let full = correlate(&reference, &deformed, guess, false);
        assert_eq!(predicted, full, "from {guess:?}");
        assert_eq!(predicted.status, NodeStatus::Ok);
        assert!(
            (predicted.u_px - shift.0).abs() < 0.02 && (predicted.v_px - shift.1).abs() < 0.02,
            "from {guess:?}: {predicted:?}"
        );
    }
}

/// A ZOI of another image (`correlate_uncached`, the measurements against the origin) prepares
/// only what its correlation uses, and gives what the cached reference gives: the same
/// displacement (to 1e-9 px), score, status and iterations, and the same integer searches, for
/// a confirmed prediction, one several pixels off, without a prediction, warped, and flat.
#[test]
fn an_uncached_zoi_correlates_as_a_cached_one() {
    let reference = speckle((0.0, 0.0));
    let flat = vec![3000u16; SIZE * SIZE];
    let shift = (1.37, -0.71);
    let deformed = speckle(shift);
    let warps = [None, Some([[0.02, -0.01], [0.015, -0.03]])];
    let guesses = [(1.4, -0.7), (1.0, -1.0), (5.4, -3.7)];
    let mut cases = 0;
    for reference in [&reference, &flat] {
        for warp in warps {
            for guess_px in guesses {
                for predicted in [true, false] {
                    let search = ZoiSearch {
                        top_left_px: TOP_LEFT,
                        guess_px,
                        warp,
                        iterations: SubpixelIterations::paper(10),
                        predicted,
                    };
                    let mut cached_engine = ZoiEngine::new(N);
                    let mut plain = vec![Complex32::new(0.0, 0.0); spectrum_len(N)];
                    let mut windowed = vec![0.0; N * N];
                    let mut sensitivity = GradientSensitivity::default();
                    let contrast = cached_engine.prepare_reference(
                        image(reference),
                        TOP_LEFT.0,
                        TOP_LEFT.1,
                        &mut plain,
                        &mut windowed,
                        &mut sensitivity,
                    );
                    let spectra = ReferenceSpectra {
                        plain: &plain,
                        windowed: &windowed,
                    };
                    let cached = if contrast {
                        cached_engine.correlate(&spectra, image(&deformed), search)
                    } else {
                        ZoiResult::with_status(NodeStatus::LowContrast, 0)
                    };
                    let mut engine = ZoiEngine::new(N);
                    // Twice on one engine: nothing of a ZOI stays behind for the next.
                    for _ in 0..2 {
                        let uncached =
                            engine.correlate_uncached(image(reference), image(&deformed), search);
                        let context = format!("{warp:?} {guess_px:?} {predicted}");
                        assert!((uncached.u_px - cached.u_px).abs() <= 1e-9, "{context}");
                        assert!((uncached.v_px - cached.v_px).abs() <= 1e-9, "{context}");
                        assert_eq!(uncached.score, cached.score, "{context}");
                        assert_eq!(uncached.status, cached.status, "{context}");
                        assert_eq!(uncached.iterations, cached.iterations, "{context}");
                        assert_eq!(uncached.warp_gradient, cached.warp_gradient, "{context}");
                    }
                    assert_eq!(engine.searches, 2 * cached_engine.searches);
                    cases += usize::from(contrast && cached.status == NodeStatus::Ok);
                }
            }
        }
    }
    // Every measurable case measured: 2 warps x 3 guesses x 2 on the speckle.
    assert_eq!(cases, 12);
}
