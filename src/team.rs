//! A team of spinning helper threads for short parallel regions repeated at a high rate: the
//! explicit driver's gradient, tens to hundreds of microseconds per step, millions of steps.
//!
//! Rayon's idle workers go to sleep a few microseconds after their last job. Waking a sleeping
//! thread goes through the kernel (a futex), and on a virtual machine whose idle CPU has been
//! halted, through the hypervisor: measured on a 2-vCPU KVM guest, the fork and the join of one
//! parallel region cost 15–100 µs together, as much as the work of a 2000-face step. The helpers
//! here instead spin on an epoch counter between regions (with the CPU's spin-wait hint), so a
//! region starts and ends within about a microsecond. A helper that sees no region for
//! [`SPIN`] parks on a condition variable and is woken through it.
//!
//! A team is created for one hot loop and activated on the calling thread with
//! [`Team::activate`]; [`with_active`] lets code deep in the call chain (the element assembly)
//! find it without threading it through every signature. Code that finds no active team uses
//! rayon. Dropping the team stops and joins its helpers.
//!
//! Who runs which part never changes a result: callers split their work into parts whose
//! outputs do not depend on the thread that computes them.

use std::cell::UnsafeCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long an idle helper spins before it parks: longer than the serial part between two
/// regions of a hot loop (the update of positions and velocities, a check of the state), short
/// enough that a finished loop does not keep a core busy for long.
pub const SPIN: Duration = Duration::from_millis(2);

/// A region's work: called once per part with the part's index.
type Job = dyn Fn(usize) + Sync;

/// State shared by the caller and the helpers.
struct Shared {
    /// Incremented by the caller to start a region.
    epoch: AtomicU64,
    /// Helpers that have finished the current region.
    done: AtomicUsize,
    /// The current region's work, valid from an `epoch` increment until `done` reaches the
    /// helper count.
    job: UnsafeCell<*const Job>,
    /// Helpers parked on `wake`.
    sleepers: AtomicUsize,
    lock: Mutex<()>,
    wake: Condvar,
    /// A helper's part panicked in the current region.
    panicked: AtomicBool,
    /// The team is being dropped.
    quit: AtomicBool,
    /// A region is running: a second caller must not start one.
    running: AtomicBool,
}

// SAFETY: `job` is written only by the caller while no region is running (every helper has
// reported `done` for the previous one) and read by helpers only after the `epoch` increment
// that publishes it (release/acquire), until they report `done`.
unsafe impl Sync for Shared {}
unsafe impl Send for Shared {}

/// A caller thread plus `helpers` spinning threads; see the module doc.
pub struct Team {
    shared: Arc<Shared>,
    handles: Vec<JoinHandle<()>>,
}

thread_local! {
    static ACTIVE: std::cell::Cell<*const Team> = const { std::cell::Cell::new(std::ptr::null()) };
}

/// Puts back the thread's active team when dropped (also on a panic).
struct Restore(*const Team);

impl Drop for Restore {
    fn drop(&mut self) {
        ACTIVE.with(|a| a.set(self.0));
    }
}

impl Team {
    /// A team of `threads` threads in all: the caller and `threads − 1` helpers.
    pub fn new(threads: usize) -> Team {
        let shared = Arc::new(Shared {
            epoch: AtomicU64::new(0),
            done: AtomicUsize::new(0),
            job: UnsafeCell::new(std::ptr::null::<fn(usize)>() as *const Job),
            sleepers: AtomicUsize::new(0),
            lock: Mutex::new(()),
            wake: Condvar::new(),
            panicked: AtomicBool::new(false),
            quit: AtomicBool::new(false),
            running: AtomicBool::new(false),
        });
        let handles = (1..threads.max(1))
            .map(|part| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("shellsim-team-{part}"))
                    .spawn(move || helper(&shared, part))
                    .expect("cannot start a helper thread")
            })
            .collect();
        Team { shared, handles }
    }

    /// Threads in the team, the caller included.
    pub fn threads(&self) -> usize {
        self.handles.len() + 1
    }

    /// Runs `job(p)` for every part `p < threads()`, part 0 on the caller, and returns when all
    /// have finished. A panic in any part is re-raised here once every part has finished.
    pub fn run(&self, job: &(dyn Fn(usize) + Sync)) {
        let helpers = self.handles.len();
        if helpers == 0 {
            job(0);
            return;
        }
        let s = &*self.shared;
        // One region at a time: `job` and `done` belong to it.
        assert!(
            !s.running.swap(true, Ordering::Acquire),
            "a team runs one parallel region at a time"
        );
        // SAFETY: no region is running (the previous `run` waited for every helper), so no
        // helper reads `job`; the lifetime is erased because `run` does not return before
        // every helper is done with it.
        unsafe {
            *s.job.get() = std::mem::transmute::<&(dyn Fn(usize) + Sync), *const Job>(job);
        }
        s.done.store(0, Ordering::Relaxed);
        s.epoch.fetch_add(1, Ordering::SeqCst);
        if s.sleepers.load(Ordering::SeqCst) > 0 {
            let _g = s.lock.lock().unwrap_or_else(|p| p.into_inner());
            s.wake.notify_all();
        }
        let mine = catch_unwind(AssertUnwindSafe(|| job(0)));
        let mut spins = 0u32;
        while s.done.load(Ordering::Acquire) < helpers {
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(4096) {
                // A helper descheduled by the OS: let it have the core.
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        s.running.store(false, Ordering::Release);
        // Cleared whatever happens, so that the next region does not report this one's panic.
        let helper_panicked = s.panicked.swap(false, Ordering::Relaxed);
        if let Err(payload) = mine {
            std::panic::resume_unwind(payload);
        }
        if helper_panicked {
            panic!("a part of a parallel region panicked on a helper thread");
        }
    }

    /// Runs `f` with this team active on the calling thread: [`with_active`] finds it there.
    pub fn activate<R>(&self, f: impl FnOnce() -> R) -> R {
        let _restore = Restore(ACTIVE.with(|a| a.replace(self as *const Team)));
        f()
    }
}

/// Calls `f` with the team active on this thread, if there is one (and it is not already
/// running a region: a region's parts see none).
pub fn with_active<R>(f: impl FnOnce(Option<&Team>) -> R) -> R {
    let p = ACTIVE.with(|a| a.replace(std::ptr::null()));
    let _restore = Restore(p);
    // SAFETY: a non-null pointer was set by `activate`, whose borrow of the team outlives the
    // call of `f` it wraps; it is cleared while `f` runs, so a nested call sees no team.
    f(unsafe { p.as_ref() })
}

/// A helper's loop: wait for a new epoch (spinning, then parked), run its part, report.
fn helper(s: &Shared, part: usize) {
    let mut seen = 0u64;
    loop {
        let start = Instant::now();
        let mut spins = 0u32;
        loop {
            if s.epoch.load(Ordering::Acquire) != seen || s.quit.load(Ordering::Relaxed) {
                break;
            }
            spins = spins.wrapping_add(1);
            if !spins.is_multiple_of(1024) {
                std::hint::spin_loop();
                continue;
            }
            if start.elapsed() <= SPIN {
                // On a host with more runnable threads than cores, let the caller have the
                // core now and then (tens of microseconds apart): its serial work is what the
                // helper waits for.
                std::thread::yield_now();
            } else {
                let mut g = s.lock.lock().unwrap_or_else(|p| p.into_inner());
                s.sleepers.fetch_add(1, Ordering::SeqCst);
                while s.epoch.load(Ordering::SeqCst) == seen && !s.quit.load(Ordering::SeqCst) {
                    g = s.wake.wait(g).unwrap_or_else(|p| p.into_inner());
                }
                s.sleepers.fetch_sub(1, Ordering::SeqCst);
                break;
            }
        }
        if s.quit.load(Ordering::Acquire) {
            return;
        }
        seen = s.epoch.load(Ordering::Acquire);
        // SAFETY: see `Shared`: published by the epoch increment just observed.
        let job = unsafe { &**s.job.get() };
        if catch_unwind(AssertUnwindSafe(|| job(part))).is_err() {
            s.panicked.store(true, Ordering::Relaxed);
        }
        s.done.fetch_add(1, Ordering::Release);
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        let s = &*self.shared;
        s.quit.store(true, Ordering::SeqCst);
        {
            let _g = s.lock.lock().unwrap_or_else(|p| p.into_inner());
            s.wake.notify_all();
        }
        for h in self.handles.drain(..) {
            let _ = h.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_part_runs_once_per_region_and_panics_reach_the_caller() {
        for threads in 1..=3 {
            let team = Team::new(threads);
            let counts: Vec<AtomicUsize> = (0..threads).map(|_| AtomicUsize::new(0)).collect();
            for _ in 0..1000 {
                team.run(&|p| {
                    counts[p].fetch_add(1, Ordering::Relaxed);
                });
            }
            // Past the spin: the helpers park and must be woken.
            std::thread::sleep(SPIN * 3);
            team.run(&|p| {
                counts[p].fetch_add(1, Ordering::Relaxed);
            });
            assert!(counts.iter().all(|c| c.load(Ordering::Relaxed) == 1001));
            if threads > 1 {
                let r = catch_unwind(AssertUnwindSafe(|| {
                    team.run(&|p| assert!(p != threads - 1, "boom"));
                }));
                assert!(r.is_err());
                // Every part panics: the caller's panic is raised, and the helpers' is not
                // left over for the next region.
                let all = catch_unwind(AssertUnwindSafe(|| team.run(&|_| panic!("all"))));
                assert!(all.is_err());
                // A region started inside a region is refused, not a data race.
                let nested = catch_unwind(AssertUnwindSafe(|| {
                    team.run(&|p| {
                        if p == 0 {
                            team.run(&|_| {});
                        }
                    });
                }));
                assert!(nested.is_err());
                // The team still works after a panic.
                team.run(&|p| {
                    counts[p].fetch_add(1, Ordering::Relaxed);
                });
                assert!(counts.iter().all(|c| c.load(Ordering::Relaxed) == 1002));
            }
        }
    }
}
