//! Fork-join on two threads for the iteration's short parallel loops, with a helper thread
//! that keeps spinning between them instead of going to sleep.
//!
//! Why not `rayon::join` there: every iteration runs four joins of 50-150 us halves between
//! serial stages (contacts, residual) of 20-50 us, and rayon's idle workers go to sleep within
//! microseconds; waking one costs 20-40 us on the 2-core VM. Measured there: a join of two
//! 22 us halves between 20 us of serial work took 84 us from the main thread (62-67 us inside
//! the pool), against 66 us serially and 42 us ideally.
//!
//! Used only where both cores are the step's: outside a rayon pool (the main thread of
//! `simulate`, `demo`, `predict`) with at least two threads. Inside a pool (synthesis runs
//! sequences on every core) and for a second caller while the helper is taken, it is
//! `rayon::join`. A caller that finishes its half before the helper has started the other
//! takes that one back and runs it too: with another process on the second core the helper
//! is often off it, and waiting for the scheduler made a join cost milliseconds (the skirt
//! walk with a busy loop beside it: 2.7-4.1 frames/s before, 5.4-6.5 after; 10-13 alone).
//! Which thread runs which half never changes a result. Written by hand: no crate offers a
//! join that spins across the gaps of a serial loop.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// How long the helper spins after a task before it sleeps: longer than the serial stages
/// between an iteration's joins, shorter than a step's detection, which needs both cores.
const SPIN: Duration = Duration::from_micros(200);

/// Busy-wait rounds before a waiting thread starts yielding its core.
const SPIN_ROUNDS: u32 = 2000;

/// The task of the current join, its lifetime erased (see [`join`]).
struct Task(*mut (dyn FnMut() + Send + 'static));

// SAFETY: the closure behind the pointer is `Send`; the pointer itself only crosses to the
// helper, which calls it once while `join` waits.
unsafe impl Send for Task {}

struct Helper {
    /// Tasks posted so far, and the last task the helper finished.
    posted: AtomicUsize,
    done: AtomicUsize,
    /// The posted task and its number, until the helper or the poster takes it.
    task: Mutex<Option<(usize, Task)>>,
    /// Whether the last task panicked.
    panicked: AtomicBool,
    /// Whether the helper sleeps on `wake`.
    sleeping: Mutex<bool>,
    wake: Condvar,
    /// Taken by the one `join` that uses the helper.
    taken: AtomicBool,
}

/// The helper, started on first use; `None` if the thread cannot be started (then every
/// join is rayon's).
fn helper() -> Option<&'static Helper> {
    static HELPER: OnceLock<Option<&'static Helper>> = OnceLock::new();
    *HELPER.get_or_init(|| {
        let helper: &'static Helper = Box::leak(Box::new(Helper {
            posted: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            task: Mutex::new(None),
            panicked: AtomicBool::new(false),
            sleeping: Mutex::new(false),
            wake: Condvar::new(),
            taken: AtomicBool::new(false),
        }));
        std::thread::Builder::new()
            .name("sim-join".into())
            .spawn(move || helper.serve())
            .ok()
            .map(|_| helper)
    })
}

impl Helper {
    fn serve(&self) {
        let mut seen = 0;
        loop {
            self.wait_for_task(seen);
            seen = self.posted.load(Ordering::SeqCst);
            // Empty when the poster finished its own half first and took the task back.
            let task = self.task.lock().unwrap_or_else(|e| e.into_inner()).take();
            if let Some((job, Task(task))) = task {
                // SAFETY: `join` keeps the closure alive and untouched until `done` says this
                // task has finished (see there).
                let run = AssertUnwindSafe(|| unsafe { (*task)() });
                if catch_unwind(run).is_err() {
                    self.panicked.store(true, Ordering::SeqCst);
                }
                self.done.store(job, Ordering::Release);
            }
        }
    }

    /// Spins, then yields, then sleeps until a task after the first `seen` is posted.
    fn wait_for_task(&self, seen: usize) {
        let started = Instant::now();
        let mut rounds = 0;
        while self.posted.load(Ordering::SeqCst) == seen {
            if rounds < SPIN_ROUNDS {
                std::hint::spin_loop();
                rounds += 1;
            } else if started.elapsed() < SPIN {
                std::thread::yield_now();
            } else {
                let mut sleeping = self.sleeping.lock().unwrap_or_else(|e| e.into_inner());
                *sleeping = true;
                while self.posted.load(Ordering::SeqCst) == seen {
                    sleeping = self.wake.wait(sleeping).unwrap_or_else(|e| e.into_inner());
                }
                *sleeping = false;
            }
        }
    }

    fn post(&self, task: Task) -> usize {
        let job = self.posted.load(Ordering::SeqCst) + 1;
        *self.task.lock().unwrap_or_else(|e| e.into_inner()) = Some((job, task));
        self.posted.store(job, Ordering::SeqCst);
        if *self.sleeping.lock().unwrap_or_else(|e| e.into_inner()) {
            self.wake.notify_one();
        }
        job
    }

    fn wait_done(&self, job: usize) {
        let mut rounds = 0;
        while self.done.load(Ordering::Acquire) < job {
            if rounds < SPIN_ROUNDS {
                std::hint::spin_loop();
                rounds += 1;
            } else {
                std::thread::yield_now();
            }
        }
    }
}

/// Runs `a` here and `b` on the helper thread, and returns both results (see the module docs
/// for when it is `rayon::join` instead).
pub(crate) fn join<RA: Send, RB: Send>(
    a: impl FnOnce() -> RA + Send,
    b: impl FnOnce() -> RB + Send,
) -> (RA, RB) {
    if rayon::current_thread_index().is_some() || rayon::current_num_threads() < 2 {
        return rayon::join(a, b);
    }
    let Some(helper) = helper() else {
        return rayon::join(a, b);
    };
    if helper
        .taken
        .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
        .is_err()
    {
        return rayon::join(a, b);
    }
    let mut b = Some(b);
    let mut rb = None;
    let mut task = || rb = b.take().map(|b| b());
    let task: *mut (dyn FnMut() + Send + '_) = &mut task;
    // SAFETY: only the lifetime changes. The helper calls the closure before it raises `done`
    // to this job, and this function waits for that before it returns or unwinds (`a`'s panic
    // is caught and resumed after the wait), so the closure and what it borrows outlive
    // every use.
    let task: *mut (dyn FnMut() + Send + 'static) = unsafe { std::mem::transmute(task) };
    let job = helper.post(Task(task));
    let ra = catch_unwind(AssertUnwindSafe(a));
    // A helper that has not started the task by now lost its core (another process runs
    // there, or it slept): waiting for it would cost a scheduler slice, so take it back.
    let unstarted = helper.task.lock().unwrap_or_else(|e| e.into_inner()).take();
    let b_panicked = match unstarted {
        // SAFETY: as the helper would (see above); the helper no longer sees the task.
        Some((_, Task(task))) => catch_unwind(AssertUnwindSafe(|| unsafe { (*task)() })).is_err(),
        None => {
            helper.wait_done(job);
            helper.panicked.swap(false, Ordering::SeqCst)
        }
    };
    helper.taken.store(false, Ordering::Release);
    let ra = ra.unwrap_or_else(|panic| resume_unwind(panic));
    assert!(!b_panicked, "a task of the parallel solve panicked");
    (ra, rb.expect("the helper ran the task"))
}

/// Runs `body(offset, part)` on two parts of `items` with [`join`], split where the
/// compressed-row pointer `ptr` (one row per item) reaches half of its entries, so both parts
/// carry about equal work.
pub(crate) fn halves<T: Send>(
    items: &mut [T],
    ptr: &[usize],
    body: impl Fn(usize, &mut [T]) + Sync,
) {
    let entries = ptr.last().copied().unwrap_or(0);
    let mid = ptr.partition_point(|&p| p < entries / 2).min(items.len());
    let (first, second) = items.split_at_mut(mid);
    join(|| body(0, first), || body(mid, second));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_halves_run_with_their_borrows() {
        for round in 0..1000usize {
            let mut data = vec![0usize; 100];
            let (left, right) = data.split_at_mut(50);
            let (a, b) = join(
                || {
                    left.iter_mut().for_each(|x| *x = round);
                    left.len()
                },
                || {
                    right.iter_mut().for_each(|x| *x = round + 1);
                    right.len() * 2
                },
            );
            assert_eq!((a, b), (50, 100));
            assert!(data[..50].iter().all(|&x| x == round));
            assert!(data[50..].iter().all(|&x| x == round + 1));
        }
    }

    #[test]
    fn halves_cover_every_item_once_from_many_threads() {
        // Several callers at once: one gets the helper, the others fall back to rayon.
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    for n in [0usize, 1, 7, 1000] {
                        let mut items = vec![0usize; n];
                        // Row i has i entries: the split falls past the middle.
                        let ptr: Vec<usize> = (0..=n).map(|i| i * (i + 1) / 2).collect();
                        halves(&mut items, &ptr, |offset, part| {
                            for (k, x) in part.iter_mut().enumerate() {
                                *x += offset + k + 1;
                            }
                        });
                        assert!(items.iter().enumerate().all(|(i, &x)| x == i + 1));
                    }
                });
            }
        });
    }

    #[test]
    fn joins_stay_right_while_other_threads_take_the_cores() {
        // Busy threads on every core: the helper often loses its core, and the caller then
        // runs both halves itself.
        let stop = AtomicBool::new(false);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    while !stop.load(Ordering::Relaxed) {
                        std::hint::spin_loop();
                    }
                });
            }
            for round in 0..2000usize {
                let (a, b) = join(|| round * 2, || round * 3);
                assert_eq!((a, b), (round * 2, round * 3));
            }
            stop.store(true, Ordering::Relaxed);
        });
    }

    #[test]
    fn a_panic_in_either_half_reaches_the_caller_after_both_ran() {
        let finished = AtomicBool::new(false);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            join(
                || panic!("first half"),
                || {
                    std::thread::sleep(Duration::from_millis(20));
                    finished.store(true, Ordering::SeqCst);
                },
            )
        }));
        assert!(caught.is_err());
        assert!(
            finished.load(Ordering::SeqCst),
            "the caller waited for the helper"
        );
        let caught = catch_unwind(|| join(|| 1, || -> usize { panic!("second half") }));
        assert!(caught.is_err());
        // The helper still serves.
        assert_eq!(join(|| 2, || 3), (2, 3));
    }
}
