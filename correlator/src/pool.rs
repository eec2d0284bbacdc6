//! A tiny persistent thread pool: each worker owns one `ZoiEngine` for its whole life, jobs are
//! index ranges handed out in chunks through one atomic counter. The calling thread is worker 0,
//! so `threads = 1` spawns nothing. Starting a job takes one mutex and one condvar broadcast;
//! nothing is allocated per job or per item.

use crate::zoi::ZoiEngine;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// Items claimed at a time by a worker.
const CHUNK: usize = 4;

type JobFn = dyn Fn(&mut ZoiEngine, usize) + Sync;

#[derive(Clone, Copy)]
struct JobPtr {
    f: *const JobFn,
    items: usize,
}
// SAFETY: the pointee is `Sync` and `run` does not return before every worker is done with it.
unsafe impl Send for JobPtr {}

struct State {
    generation: u64,
    job: Option<JobPtr>,
    busy_workers: usize,
    shutdown: bool,
}

struct Shared {
    state: Mutex<State>,
    start: Condvar,
    done: Condvar,
    next: AtomicUsize,
    panicked: AtomicBool,
    engines: Vec<Mutex<ZoiEngine>>,
}

pub struct Pool {
    shared: Arc<Shared>,
    handles: Vec<JoinHandle<()>>,
}

impl Pool {
    /// `threads` workers with an engine for ZOIs of `zoi_px` and `subset_scratch` values of
    /// IC-GN scratch each.
    pub fn new(threads: usize, zoi_px: usize, subset_scratch: usize) -> Self {
        assert!(threads >= 1);
        let engines = (0..threads)
            .map(|_| {
                let mut engine = ZoiEngine::new(zoi_px);
                engine.subset_scratch = vec![0.0; subset_scratch];
                Mutex::new(engine)
            })
            .collect();
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                generation: 0,
                job: None,
                busy_workers: 0,
                shutdown: false,
            }),
            start: Condvar::new(),
            done: Condvar::new(),
            next: AtomicUsize::new(0),
            panicked: AtomicBool::new(false),
            engines,
        });
        let handles = (1..threads)
            .map(|worker| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("correlator-{worker}"))
                    .spawn(move || worker_loop(&shared, worker))
                    .expect("spawn correlator worker thread")
            })
            .collect();
        Self { shared, handles }
    }

    pub fn threads(&self) -> usize {
        self.shared.engines.len()
    }

    /// Engine of worker `i` (for reference preparation on the caller and for profiling).
    pub fn engine(&self, i: usize) -> std::sync::MutexGuard<'_, ZoiEngine> {
        self.shared.engines[i]
            .lock()
            .expect("engine mutex poisoned")
    }

    /// Calls `f(engine, item)` for every item in 0..items, spread over all workers; returns
    /// when all are done.
    pub fn run(&self, items: usize, f: &(dyn Fn(&mut ZoiEngine, usize) + Sync)) {
        if items == 0 {
            return;
        }
        // SAFETY: erase the lifetime; the pointer is cleared and every worker has finished
        // with it before this function returns (we wait for busy_workers == 0).
        let f: *const JobFn = unsafe {
            std::mem::transmute::<*const (dyn Fn(&mut ZoiEngine, usize) + Sync + '_), *const JobFn>(
                f,
            )
        };
        let job = JobPtr { f, items };
        let helpers = self.handles.len();
        {
            let mut state = self.shared.state.lock().expect("pool mutex poisoned");
            self.shared.next.store(0, Ordering::SeqCst);
            state.job = Some(job);
            state.generation += 1;
            state.busy_workers = helpers;
        }
        self.shared.start.notify_all();
        let caller_result =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&self.shared, 0, job)));
        let mut state = self.shared.state.lock().expect("pool mutex poisoned");
        while state.busy_workers > 0 {
            state = self.shared.done.wait(state).expect("pool mutex poisoned");
        }
        state.job = None;
        drop(state);
        if let Err(panic) = caller_result {
            std::panic::resume_unwind(panic);
        }
        assert!(
            !self.shared.panicked.load(Ordering::SeqCst),
            "a correlator worker thread panicked"
        );
    }
}

fn work(shared: &Shared, worker: usize, job: JobPtr) {
    let mut engine = shared.engines[worker]
        .lock()
        .expect("engine mutex poisoned");
    // SAFETY: see JobPtr.
    let f = unsafe { &*job.f };
    loop {
        let first = shared.next.fetch_add(CHUNK, Ordering::Relaxed);
        if first >= job.items {
            break;
        }
        for item in first..(first + CHUNK).min(job.items) {
            f(&mut engine, item);
        }
    }
}

fn worker_loop(shared: &Shared, worker: usize) {
    let mut seen = 0u64;
    loop {
        let job = {
            let mut state = shared.state.lock().expect("pool mutex poisoned");
            while state.generation == seen && !state.shutdown {
                state = shared.start.wait(state).expect("pool mutex poisoned");
            }
            if state.shutdown {
                return;
            }
            seen = state.generation;
            state.job.expect("job set with the generation")
        };
        let outcome =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(shared, worker, job)));
        if outcome.is_err() {
            shared.panicked.store(true, Ordering::SeqCst);
        }
        let mut state = shared.state.lock().expect("pool mutex poisoned");
        state.busy_workers -= 1;
        if state.busy_workers == 0 {
            shared.done.notify_all();
        }
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        if let Ok(mut state) = self.shared.state.lock() {
            state.shutdown = true;
        }
        self.shared.start.notify_all();
        for handle in self.handles.drain(..) {
            let _ = handle.join();
        }
    }
}

/// A slice that pool items write in disjoint parts: made from a `&'a mut [T]`, which it keeps
/// borrowed for `'a`, so the slice can be neither used nor freed while items write through it;
/// the slices it hands out live no longer than the borrow of the `SharedSlice` they come from.
#[derive(Clone, Copy)]
pub struct SharedSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    borrow: PhantomData<&'a mut [T]>,
}
// SAFETY: users write each index from at most one item, and read only indices no item of the
// current job writes; the pointee is exclusively borrowed for 'a, so nothing else touches it.
unsafe impl<T: Send> Send for SharedSlice<'_, T> {}
unsafe impl<T: Send> Sync for SharedSlice<'_, T> {}

impl<'a, T: Copy> SharedSlice<'a, T> {
    pub fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            borrow: PhantomData,
        }
    }
    /// # Safety
    /// No other item of the running job may access index `i`.
    #[inline]
    pub unsafe fn write(&self, i: usize, value: T) {
        assert!(i < self.len);
        // SAFETY: in bounds (asserted) of a slice borrowed for 'a; exclusive per the contract.
        unsafe { self.ptr.add(i).write(value) }
    }
    /// # Safety
    /// No item of the running job may write index `i`.
    #[inline]
    pub unsafe fn read(&self, i: usize) -> T {
        assert!(i < self.len);
        // SAFETY: in bounds (asserted); no concurrent write per the contract.
        unsafe { self.ptr.add(i).read() }
    }
}

impl<'a, T> SharedSlice<'a, T> {
    /// The first element, for items that split the slice in ways `slice_mut` cannot say
    /// (strided columns). Valid while this `SharedSlice` is borrowed.
    #[inline]
    pub fn as_mut_ptr(&self) -> *mut T {
        self.ptr
    }

    /// `start..start + len` of the slice, for as long as this `SharedSlice` is borrowed (never
    /// longer than the `'a` borrow of the slice it was made from).
    ///
    /// # Safety
    /// No other item of the running job may access `start..start + len`.
    // Several items hold disjoint parts at once through one shared `SharedSlice`: the
    // exclusivity `&mut` promises is the caller's contract below, as with `UnsafeCell`.
    #[allow(clippy::mut_from_ref)]
    #[inline]
    pub unsafe fn slice_mut(&self, start: usize, len: usize) -> &mut [T] {
        assert!(start + len <= self.len);
        // SAFETY: in bounds (asserted) of a slice exclusively borrowed for 'a, which outlives
        // the borrow of `self` the result is tied to; disjoint from every other item's part
        // per the contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(start), len) }
    }
}
