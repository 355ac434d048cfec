//! A spinning team for the parallel phases of a step.
//!
//! A step of the solver alternates parallel phases (stress; on large models also force
//! gather and predictor, contact interpolation, update and energy sums) with short serial
//! ones (time step, contact forces, constraints). A phase is a loop over fixed chunks
//! `0..n`: the calling thread claims chunks from the front, the team's helpers (rayon
//! workers held spinning between phases) from the back, each chunk exactly once. Results go
//! to per-chunk slots and are combined in chunk order, so they do not depend on which
//! thread ran what or on the number of threads. Claiming from the two ends keeps each
//! thread on about the same chunks from step to step (their data stays in its cache; an
//! interleaved claim, tried first, made the Taylor bar 18 % slower), and a phase starts and
//! ends with a few atomic operations instead of a fork-join. Measured on the Taylor bar
//! (q2, 2 threads, 16 000 steps): the stress phase took 0.06-0.10 s more wall time than
//! its busier thread's chunks, where the rayon region it replaces took 0.2 s more; an
//! empty phase costs about 0.3 us.
//!
//! Helpers wait spinning for at most [`MAX_IDLE`] after their last phase, then return to
//! rayon; the next phase spawns them again. A panic in a helper's chunk is caught, the
//! chunk counted as done, and the panic resumed on the calling thread.

use std::any::Any;
use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::ops::Range;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Longest time a helper spins waiting for the next phase.
pub const MAX_IDLE: Duration = Duration::from_micros(500);

/// Bit of [`Shared::state`] set while a phase accepts helpers.
const OPEN: u64 = 1 << 31;
/// Mask of the count of helpers inside the phase.
const INSIDE: u64 = OPEN - 1;

/// The body of the open phase, with its lifetime erased: valid while the phase is open or
/// a helper is inside it (the calling thread waits for both to end before returning).
type Body = *const (dyn Fn(usize) + Sync);

/// A value alone on its cache line(s), so that threads writing different values do not
/// invalidate each other's copies.
#[repr(align(128))]
#[derive(Default)]
struct Padded<T>(T);

struct Shared {
    /// Phase number (bits 32..64), [`OPEN`], helpers inside ([`INSIDE`]).
    state: Padded<AtomicU64>,
    body: UnsafeCell<Option<Body>>,
    /// Next chunk from the front (bits 0..32) and one past the last unclaimed (32..64).
    ends: Padded<AtomicU64>,
    /// Chunks completed by the helpers in the open phase (added as each leaves).
    done: Padded<AtomicUsize>,
    /// Helpers alive (spinning or inside a phase).
    helpers: AtomicUsize,
    /// Set when the team is dropped: helpers leave at once.
    dropped: AtomicBool,
    /// The first panic of a helper in the open phase.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

// SAFETY: `body` is written only by the calling thread while no helper can read it (the
// phase is closed and no helper is inside), and read by helpers only after joining an open
// phase (Acquire on `state`, which the calling thread set with Release after the write).
unsafe impl Sync for Shared {}
// SAFETY: as above; the pointer is only dereferenced under that protocol.
unsafe impl Send for Shared {}

/// A team of the calling thread and up to `rayon::current_num_threads() - 1` helpers.
pub struct Team {
    shared: Arc<Shared>,
}

impl Default for Team {
    fn default() -> Team {
        Team {
            shared: Arc::new(Shared {
                state: Padded::default(),
                body: UnsafeCell::new(None),
                ends: Padded::default(),
                done: Padded::default(),
                helpers: AtomicUsize::new(0),
                dropped: AtomicBool::new(false),
                panic: Mutex::new(None),
            }),
        }
    }
}

/// A clone is a new team: two simulations never share helpers.
impl Clone for Team {
    fn clone(&self) -> Team {
        Team::default()
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("helpers", &self.shared.helpers.load(Ordering::Relaxed))
            .finish()
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.dropped.store(true, Ordering::Release);
    }
}

impl Shared {
    /// Claims the next chunks, from the back for helpers and from the front otherwise:
    /// a quarter of those left (at least one), so that a phase takes few claims, each a
    /// cache-line transfer, and the last claims are single chunks that even out the ends.
    fn claim(&self, back: bool) -> Option<Range<usize>> {
        let mut cur = self.ends.0.load(Ordering::Relaxed);
        loop {
            let (lo, hi) = (cur & 0xffff_ffff, cur >> 32);
            if lo >= hi {
                return None;
            }
            let take = ((hi - lo) / 4).max(1);
            let (next, range) = if back {
                (lo | ((hi - take) << 32), hi - take..hi)
            } else {
                ((lo + take) | (hi << 32), lo..lo + take)
            };
            match self
                .ends
                .0
                .compare_exchange_weak(cur, next, Ordering::Relaxed, Ordering::Relaxed)
            {
                Ok(_) => return Some(range.start as usize..range.end as usize),
                Err(now) => cur = now,
            }
        }
    }

    /// Runs chunks of the open phase until none is left; returns how many it ran. A
    /// helper (`back`) catches a panic of a chunk for the calling thread.
    fn work(&self, body: &(dyn Fn(usize) + Sync), back: bool) -> usize {
        let mut ran = 0;
        while let Some(range) = self.claim(back) {
            ran += range.len();
            if back {
                if let Err(p) = catch_unwind(AssertUnwindSafe(|| range.rev().for_each(body))) {
                    self.panic
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .get_or_insert(p);
                }
            } else {
                range.for_each(body);
            }
        }
        ran
    }

    /// A helper: joins each new phase it sees open, leaves after `MAX_IDLE` without one.
    fn help(&self) {
        let mut seen = u64::MAX;
        let mut idle = Instant::now();
        let mut spins = 0u32;
        while !self.dropped.load(Ordering::Relaxed) {
            let s = self.state.0.load(Ordering::Acquire);
            if s & OPEN != 0 && s >> 32 != seen {
                if self
                    .state
                    .0
                    .compare_exchange_weak(s, s + 1, Ordering::Acquire, Ordering::Relaxed)
                    .is_ok()
                {
                    seen = s >> 32;
                    // SAFETY: joined an open phase, whose body outlives our stay (module
                    // protocol: the caller waits until no helper is inside).
                    let body = unsafe { &*(*self.body.get()).expect("open phase has a body") };
                    let ran = self.work(body, true);
                    self.done.0.fetch_add(ran, Ordering::Release);
                    self.state.0.fetch_sub(1, Ordering::Release);
                    idle = Instant::now();
                }
                continue;
            }
            spins += 1;
            if spins % 64 == 0 && idle.elapsed() > MAX_IDLE {
                break;
            }
            std::hint::spin_loop();
        }
        self.helpers.fetch_sub(1, Ordering::Release);
    }
}

impl Team {
    /// Runs `body(c)` for every chunk `c` in `0..chunks`, each once, on this thread and the
    /// team's helpers, and returns when all are done. A panic in any chunk is resumed here.
    pub fn for_each(&self, chunks: usize, body: &(dyn Fn(usize) + Sync)) {
        assert!(chunks < (1 << 31), "too many chunks in one phase");
        let sh = &*self.shared;
        let want = rayon::current_num_threads().saturating_sub(1);
        if want == 0 || chunks < 2 {
            (0..chunks).for_each(body);
            return;
        }
        while sh.helpers.load(Ordering::Acquire) < want {
            sh.helpers.fetch_add(1, Ordering::AcqRel);
            let shared = self.shared.clone();
            rayon::spawn(move || shared.help());
        }
        // SAFETY: the phase is closed and no helper is inside (the previous call waited),
        // so no helper reads `body`; the erased lifetime ends before this call returns.
        unsafe {
            *sh.body.get() = Some(std::mem::transmute::<&(dyn Fn(usize) + Sync), Body>(body));
        }
        *sh.panic.lock().unwrap_or_else(|e| e.into_inner()) = None;
        sh.ends.0.store((chunks as u64) << 32, Ordering::Relaxed);
        sh.done.0.store(0, Ordering::Relaxed);
        let phase = (sh.state.0.load(Ordering::Relaxed) >> 32) + 1;
        sh.state.0.store((phase << 32) | OPEN, Ordering::Release);
        /// Closes the phase and waits for the helpers inside to leave, also when the
        /// calling thread's own chunk panics.
        struct Close<'a>(&'a Shared);
        impl Drop for Close<'_> {
            fn drop(&mut self) {
                let s = self.0.state.0.fetch_and(!OPEN, Ordering::AcqRel);
                let mut inside = s & INSIDE;
                while inside != 0 {
                    std::hint::spin_loop();
                    inside = self.0.state.0.load(Ordering::Acquire) & INSIDE;
                }
                // SAFETY: closed with no helper inside: nobody reads `body`.
                unsafe { *self.0.body.get() = None };
            }
        }
        let close = Close(sh);
        let ran = sh.work(body, false);
        while ran + sh.done.0.load(Ordering::Acquire) < chunks {
            std::hint::spin_loop();
        }
        drop(close);
        let panic = sh.panic.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(p) = panic {
            resume_unwind(p);
        }
    }
}

/// A slice whose disjoint parts are written by different members of a team in one phase.
pub struct Parts<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

// SAFETY: `Parts` hands out `&mut` to disjoint ranges only (caller's contract in `get`),
// so sharing it across threads is as safe as sending the parts.
unsafe impl<T: Send> Sync for Parts<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send> Send for Parts<'_, T> {}

impl<'a, T> Parts<'a, T> {
    /// Borrows `slice` for the phase.
    pub fn new(slice: &'a mut [T]) -> Parts<'a, T> {
        Parts {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: PhantomData,
        }
    }

    /// The elements in `range`.
    ///
    /// # Safety
    ///
    /// No other reference to an element of `range` may be alive while the result is (in a
    /// phase: each chunk takes its own range, and chunks' ranges do not overlap).
    #[allow(clippy::mut_from_ref)] // disjointness is the caller's contract
    pub unsafe fn get(&self, range: Range<usize>) -> &'a mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked); exclusive by the caller's contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }
}

/// Particle count from which the particle phases run on the team. Below it the phases take
/// a few microseconds, and handing half the particles to the other core costs more in
/// cache-line transfers than it saves (measured on the 1 071-particle Taylor bar: the
/// force, contact and update stages took 0.45-0.50 s run on one thread against 0.48-0.58 s
/// on two). The blocks and their order are the same either way, and so are the bits.
pub const PARALLEL_PARTICLES: usize = 4096;

/// Part `k` of `0..n` cut into parts of `size`: `k size..min((k + 1) size, n)`.
pub fn part(k: usize, size: usize, n: usize) -> std::ops::Range<usize> {
    k * size..((k + 1) * size).min(n)
}

/// Runs `body` over `blocks` blocks of a particle phase of a model of `particles`
/// particles: on the team from [`PARALLEL_PARTICLES`] up, else on this thread in block
/// order.
pub fn particle_phase(team: &Team, particles: usize, blocks: usize, body: &(dyn Fn(usize) + Sync)) {
    if particles >= PARALLEL_PARTICLES {
        team.for_each(blocks, body);
    } else {
        (0..blocks).for_each(body);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_chunk_runs_once_in_any_pool() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let team = Team::default();
                for n in [0, 1, 2, 7, 100] {
                    for _ in 0..50 {
                        let mut hits = vec![0u32; n];
                        let parts = Parts::new(&mut hits);
                        team.for_each(n, &|c| {
                            // SAFETY: chunk c takes element c only.
                            let hit = unsafe { parts.get(c..c + 1) };
                            hit[0] += 1;
                        });
                        assert!(
                            hits.iter().all(|&h| h == 1),
                            "{threads} threads, {n} chunks"
                        );
                    }
                }
            });
        }
    }

    #[test]
    fn a_panic_in_a_chunk_reaches_the_caller_and_the_team_goes_on() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            let team = Team::default();
            for bad in [0, 63] {
                let r = catch_unwind(AssertUnwindSafe(|| {
                    team.for_each(64, &|c| {
                        assert!(c != bad, "chunk {c} fails");
                    })
                }));
                let msg = r.expect_err("the panic must reach the caller");
                let msg = msg.downcast_ref::<String>().cloned().unwrap_or_default();
                assert_eq!(msg, format!("chunk {bad} fails"));
                let count = AtomicUsize::new(0);
                team.for_each(64, &|_| {
                    count.fetch_add(1, Ordering::Relaxed);
                });
                assert_eq!(count.into_inner(), 64);
            }
        });
    }
}
