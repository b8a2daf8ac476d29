//! Where a run's wall time goes: named phases (clock warm-up, timed frames, capture readback,
//! metrics, image saving, ...) timed with [`span`] guards on the run's thread, each phase's
//! *own* time (a nested span's time is its own, not its parent's), so the phases of a run add up
//! to the wall time they cover. `tessera run --timings` prints them per scenario and for the
//! run, and writes them to `<run>/timings.json`.
//!
//! A diagnostic of the harness, not a measure of the GPU: GPU work is asynchronous, so a phase
//! that submits without waiting is charged to the phase that next waits for the queue (a
//! capture frame's encode pass, for instance, to the next readback). Not for: timings of the
//! rendered work (`render/timers.rs`, GPU timestamps).

use std::cell::RefCell;
use std::time::{Duration, Instant};

/// One phase's total over a part of the run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Phase {
    pub name: &'static str,
    /// Seconds of wall time, the phase's own.
    pub seconds: f64,
    /// How many spans of this name ended.
    pub count: u64,
}

struct Open {
    name: &'static str,
    start: Instant,
    /// Time of the spans nested in this one.
    nested: Duration,
}

#[derive(Default)]
struct State {
    open: Vec<Open>,
    /// Totals in first-seen order.
    totals: Vec<(&'static str, Duration, u64)>,
}

thread_local! {
    static STATE: RefCell<State> = RefCell::new(State::default());
}

/// Times phase `name` until the guard drops.
#[must_use = "the phase ends when the guard is dropped"]
pub struct Span {
    _not_send: std::marker::PhantomData<*const ()>,
}

pub fn span(name: &'static str) -> Span {
    STATE.with(|s| {
        s.borrow_mut().open.push(Open {
            name,
            start: Instant::now(),
            nested: Duration::ZERO,
        })
    });
    Span {
        _not_send: std::marker::PhantomData,
    }
}

impl Drop for Span {
    fn drop(&mut self) {
        STATE.with(|s| {
            let mut s = s.borrow_mut();
            let Some(open) = s.open.pop() else {
                return;
            };
            let elapsed = open.start.elapsed();
            let own = elapsed.saturating_sub(open.nested);
            if let Some(parent) = s.open.last_mut() {
                parent.nested += elapsed;
            }
            match s.totals.iter_mut().find(|t| t.0 == open.name) {
                Some(t) => {
                    t.1 += own;
                    t.2 += 1;
                }
                None => s.totals.push((open.name, own, 1)),
            }
        })
    }
}

/// Times `f` as phase `name`.
pub fn time<T>(name: &'static str, f: impl FnOnce() -> T) -> T {
    let _span = span(name);
    f()
}

/// The totals of this thread so far, in first-seen order.
pub fn totals() -> Vec<Phase> {
    STATE.with(|s| {
        s.borrow()
            .totals
            .iter()
            .map(|&(name, d, count)| Phase {
                name,
                seconds: d.as_secs_f64(),
                count,
            })
            .collect()
    })
}

/// What was added between two [`totals`] (phases that did not change are left out).
pub fn since(before: &[Phase], after: &[Phase]) -> Vec<Phase> {
    after
        .iter()
        .filter_map(|a| {
            let b = before.iter().find(|b| b.name == a.name);
            let (s, c) = b.map_or((0.0, 0), |b| (b.seconds, b.count));
            (a.count > c).then(|| Phase {
                name: a.name,
                seconds: a.seconds - s,
                count: a.count - c,
            })
        })
        .collect()
}

/// A table of phases, largest first, with the wall time they cover and what no phase covered
/// (`other`).
pub fn table(title: &str, phases: &[Phase], wall_s: f64) -> String {
    let mut sorted = phases.to_vec();
    sorted.sort_by(|a, b| b.seconds.total_cmp(&a.seconds));
    let covered: f64 = sorted.iter().map(|p| p.seconds).sum();
    let width = sorted
        .iter()
        .map(|p| p.name.len())
        .max()
        .unwrap_or(0)
        .max(5);
    let mut out = format!("{title}: {wall_s:.2} s wall\n");
    let pct = |s: f64| {
        if wall_s > 0.0 {
            100.0 * s / wall_s
        } else {
            0.0
        }
    };
    for p in &sorted {
        out.push_str(&format!(
            "  {:<width$}  {:>9.3} s  {:>5.1}%  ({}x)\n",
            p.name,
            p.seconds,
            pct(p.seconds),
            p.count
        ));
    }
    let other = (wall_s - covered).max(0.0);
    out.push_str(&format!(
        "  {:<width$}  {:>9.3} s  {:>5.1}%\n",
        "other",
        other,
        pct(other)
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_time_is_charged_to_the_inner_phase_only() {
        let before = totals();
        {
            let _outer = span("test-outer");
            std::thread::sleep(Duration::from_millis(5));
            time("test-inner", || {
                std::thread::sleep(Duration::from_millis(20))
            });
        }
        let d = since(&before, &totals());
        let get = |n: &str| d.iter().find(|p| p.name == n).unwrap().clone();
        let (outer, inner) = (get("test-outer"), get("test-inner"));
        assert_eq!((outer.count, inner.count), (1, 1));
        assert!(inner.seconds >= 0.020);
        // The outer span's own time excludes the inner span's 20 ms.
        assert!(outer.seconds < inner.seconds);
        assert!(outer.seconds >= 0.005);
    }

    #[test]
    fn table_lists_largest_first_and_the_uncovered_rest() {
        let phases = [
            Phase {
                name: "a",
                seconds: 1.0,
                count: 2,
            },
            Phase {
                name: "bb",
                seconds: 3.0,
                count: 1,
            },
        ];
        let t = table("run", &phases, 5.0);
        let expected = [
            "run: 5.00 s wall",
            "  bb         3.000 s   60.0%  (1x)",
            "  a          1.000 s   20.0%  (2x)",
            "  other      1.000 s   20.0%",
            "",
        ];
        assert_eq!(t, expected.join("\n"));
    }
}
