//! The live shell allocates nothing per frame in steady state: a counting allocator counts the
//! allocations made on the process thread (the pool workers run the core, which
//! `no_allocation.rs` covers) between the 4th and the last field, with the status line off.
//! The only allocations allowed are iceoryx2's own, found with a backtrace per allocation:
//! its WaitSet collects the triggered file descriptors in two small vectors per wake-up
//! (`WaitSet::wait_and_process_once_with_timeout` and `handle_all_attachments`), and each
//! loaned sample gets a reference-counted shared state (`Publisher::loan_slice_uninit`):
//! three small blocks per frame, freed at once. The shell's own code adds none.

mod common;

use common::{render, translation};
use correlator::process::{run, ProcessConfig};
use correlator::{CorrelatorSettings, Method, ReferenceMode};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};
use testkit::{TestInstance, HANG_GUARD};
use wire::pubsub::{SlicePublisher, SliceSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, Instance};

thread_local! {
    static TRACKED: Cell<bool> = const { Cell::new(false) };
}
static SHELL_ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

struct Counting;

fn count() {
    if TRACKED.try_with(|t| t.get()).unwrap_or(false) {
        SHELL_ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Removes the instance's shared-memory files (the test kit's `TestInstance`) and the state
/// folder, even when the test fails.
struct Cleanup {
    _instance: TestInstance,
    state_dir: std::path::PathBuf,
}

impl Drop for Cleanup {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.state_dir);
    }
}

const W: usize = 128;
const FRAMES: u64 = 14;
/// Fields received before counting starts (publisher, caches and histograms warmed up).
const WARM_UP: u64 = 4;

fn steady_state_allocations(
    label: &str,
    method: Method,
    reference: ReferenceMode,
    with_state: bool,
) -> (usize, u64) {
    let test_instance = TestInstance::new(&format!("alloc_{label}"));
    let name = test_instance.name().to_string();
    let instance = Instance::new(&name).unwrap();
    let state_dir = std::env::temp_dir().join(format!("{name}_state"));
    let _ = std::fs::remove_dir_all(&state_dir);
    let cleanup = Cleanup {
        _instance: test_instance,
        state_dir: state_dir.clone(),
    };
    let mut config = ProcessConfig::new(
        &name,
        CorrelatorSettings {
            method,
            reference,
            threads: 2,
            ..CorrelatorSettings::default()
        },
    );
    config.max_frames = Some(FRAMES);
    config.idle_timeout = Some(Duration::from_secs(60));
    config.status_interval = Duration::from_secs(3600);
    config.state_dir = with_state.then(|| state_dir.clone());
    let shell = std::thread::spawn(move || {
        TRACKED.with(|t| t.set(true));
        run(config)
    });
    let frames: Vec<Vec<u16>> = (0..FRAMES)
        .map(|k| {
            render(
                W,
                W,
                8.0,
                translation(0.2 * k as f64, -0.1 * k as f64),
                0.01,
                k,
            )
        })
        .collect();
    let (mut before, mut after) = (0, 0);
    {
        let (node, _) = instance.create_node("alloc_test").unwrap();
        let publisher: SlicePublisher<u16, FrameHeader> =
            SlicePublisher::create(&node, &services::FRAMES, W * W).unwrap();
        let fields: SliceSubscriber<FieldNode, FieldHeader> =
            SliceSubscriber::create(&node, &services::FIELDS).unwrap();
        let send = |k: u64| {
            publisher
                .publish(W * W, |h, out| {
                    *h = FrameHeader {
                        frame_id: k,
                        width_px: W as u32,
                        height_px: W as u32,
                        ..FrameHeader::default()
                    };
                    out.copy_from_slice(&frames[k as usize]);
                    Ok::<bool, ()>(true)
                })
                .unwrap()
                .unwrap()
                .unwrap()
        };
        // Until the shell subscribed (bounded).
        let start = Instant::now();
        while send(0) == 0 {
            assert!(start.elapsed() < HANG_GUARD, "the shell never subscribed");
            std::thread::sleep(Duration::from_millis(10));
        }
        for k in 0..FRAMES {
            if k > 0 {
                send(k);
            }
            let deadline = Instant::now() + HANG_GUARD;
            let field = loop {
                if let Some(sample) = fields.receive().unwrap() {
                    break *sample.user_header();
                }
                assert!(Instant::now() < deadline, "no field for frame {k}");
                let _ = fields
                    .listener()
                    .timed_wait(|_| {}, Duration::from_millis(100));
            };
            assert_eq!(field.frame_id, k);
            if k + 1 == WARM_UP {
                before = SHELL_ALLOCATIONS.load(Ordering::SeqCst);
            }
            if k + 1 == FRAMES - 1 {
                after = SHELL_ALLOCATIONS.load(Ordering::SeqCst);
            }
        }
    }
    let summary = shell.join().unwrap().unwrap();
    assert_eq!(summary.frames_correlated, FRAMES);
    if with_state {
        // Saved off the frame path: references handed over while the writer was busy
        // replace each other, and the last one is written before the process ends.
        assert!(summary.state_saves >= 1, "{summary:?}");
        let saved = correlator::state::StateDir::open(&cleanup.state_dir)
            .unwrap()
            .load()
            .unwrap()
            .unwrap();
        assert_eq!(saved.reference_frame_id, FRAMES - 1, "{summary:?}");
    }
    drop(cleanup);
    let left = instance.leftover_files();
    assert!(left.is_empty(), "left in shared memory: {left:?}");
    let frames_counted = FRAMES - 1 - WARM_UP;
    (after - before, frames_counted)
}

#[test]
fn the_shell_allocates_nothing_per_frame_but_the_waitset() {
    for (label, method, reference, with_state) in [
        ("fixed", Method::Correli, ReferenceMode::Fixed, false),
        (
            "incremental_state",
            Method::Correli,
            ReferenceMode::Incremental,
            true,
        ),
        (
            "icgn1_incremental_state",
            Method::Icgn1,
            ReferenceMode::Incremental,
            true,
        ),
    ] {
        let (allocations, frames) = steady_state_allocations(label, method, reference, with_state);
        eprintln!(
            "{label}: {allocations} allocations on the shell thread in {frames} frames ({:.1} per frame)",
            allocations as f64 / frames as f64
        );
        // One wake-up per frame here (frames are sent one at a time): two WaitSet vectors and
        // one loan.
        assert!(
            allocations as u64 <= 3 * frames,
            "{label}: {allocations} allocations in {frames} frames"
        );
    }
}
