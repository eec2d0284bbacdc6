//! No allocation per frame in steady state: a counting global allocator watches `correlate`
//! after a warm-up frame, for every method, reference and guess mode, on 2 threads.

mod common;

use common::{render, translation};
use correlator::{Correlator, CorrelatorSettings, GuessMode, Method, ReferenceMode};
use producer::motion::{Bulge, Motion};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steady_state_allocates_nothing() {
    let (w, h) = (192, 192);
    let frames: Vec<Vec<u16>> = (0..5)
        .map(|k| {
            render(
                w,
                h,
                8.0,
                translation(0.3 * k as f64, -0.2 * k as f64),
                0.01,
                k as u64,
            )
        })
        .collect();
    let modes = [
        (ReferenceMode::Fixed, GuessMode::Correli),
        (ReferenceMode::Fixed, GuessMode::Predict),
        (ReferenceMode::Incremental, GuessMode::Predict),
        (ReferenceMode::AUTO_DEFAULT, GuessMode::Predict),
    ];
    let cases = modes
        .into_iter()
        .map(|(r, g)| (Method::Correli, 32, r, g))
        .chain(modes.into_iter().map(|(r, g)| (Method::Icgn1, 33, r, g)))
        .chain([
            (
                Method::Icgn2,
                24,
                ReferenceMode::AUTO_DEFAULT,
                GuessMode::Predict,
            ),
            (
                Method::Icgn,
                33,
                ReferenceMode::AUTO_DEFAULT,
                GuessMode::Predict,
            ),
        ]);
    for (method, zoi_px, reference, guess) in cases {
        let settings = CorrelatorSettings {
            method,
            zoi_px,
            step_px: 16,
            reference,
            guess,
            threads: 2,
            ..Default::default()
        };
        let (allocated, valid, _) = steady_frames(settings, &frames);
        assert!(valid > 0);
        assert_eq!(
            allocated, 0,
            "{method:?} {reference:?} {guess:?}: {allocated} allocations in 3 frames"
        );
    }
    second_order_re_runs_allocate_nothing();
}

/// Method `icgn` where it re-runs nodes at second order (a bulge: a curved field): no
/// allocation either, the second-order constants of a subset derived on its first re-run.
/// Called from the test above: the allocation counter is global, so the cases run in turn.
fn second_order_re_runs_allocate_nothing() {
    let (w, h) = (192, 192);
    let frames: Vec<Vec<u16>> = (0..5)
        .map(|k| {
            let bulge = Bulge {
                strain: 0.02 * k as f64,
                width_px: 30.0,
                centre_px: [96.0, 96.0],
            };
            render(w, h, 8.0, Motion::Bulge(bulge), 0.01, k as u64)
        })
        .collect();
    let settings = CorrelatorSettings {
        method: Method::Icgn,
        zoi_px: 33,
        step_px: 8,
        reference: ReferenceMode::Fixed,
        guess: GuessMode::Predict,
        threads: 2,
        ..Default::default()
    };
    let (allocated, _, runs) = steady_frames(settings, &frames);
    assert!(runs > 0, "the bulge re-ran no node at second order");
    assert_eq!(allocated, 0, "{allocated} allocations in 3 frames");
}

/// Correlates frames 2.. of `frames` (192² px) after the reference (frame 0) and a warm-up
/// frame (1): the allocations meanwhile, and the sums of those fields' valid nodes and nodes
/// re-run at second order.
fn steady_frames(settings: CorrelatorSettings, frames: &[Vec<u16>]) -> (usize, usize, usize) {
    let mut correlator = Correlator::new(settings, 192, 192).unwrap();
    correlator.set_reference(&frames[0]).unwrap();
    correlator.correlate(&frames[1]).unwrap();
    let (mut valid, mut runs) = (0, 0);
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for frame in &frames[2..] {
        let field = correlator.correlate(frame).unwrap();
        valid += field.valid;
        runs += field.second_order_runs;
    }
    (ALLOCATIONS.load(Ordering::SeqCst) - before, valid, runs)
}
