//! The sampling thread: owns a [`ConditionSource`] and reads it while a window is open, so that no
//! sensor read sits on the thread that submits and collects frames.
//!
//! [`Sampler::begin`] is a channel send (the render loop calls it as the last warm-up frame
//! completes); the thread then samples at once and every [`SAMPLE_INTERVAL_MS`] until
//! [`Sampler::end`], which takes one last sample and returns the window's samples. Between windows
//! the thread sleeps on its channel. While a window is open, [`Sampler::energy_steps`] says how
//! often the energy counter has changed in it (the energy window ends on it).

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{ConditionSource, DeviceLimits, Sample, SAMPLE_INTERVAL_MS};

enum Command {
    /// Open a window sampled at this period (`None`: the sampler's own).
    Begin(Option<Duration>),
    End,
}

pub struct Sampler {
    commands: Option<Sender<Command>>,
    windows: Receiver<Vec<Sample>>,
    thread: Option<JoinHandle<()>>,
    limits: DeviceLimits,
    /// Changes of the energy counter seen in the open window (reset when one opens).
    steps: Arc<AtomicU32>,
    /// The last sample's graphics clock in MHz (f64 bits; NaN when none was read).
    clock: Arc<AtomicU64>,
}

impl Sampler {
    /// Starts the thread with the default period.
    pub fn spawn(source: Box<dyn ConditionSource>) -> Sampler {
        Sampler::with_interval(source, Duration::from_secs_f64(SAMPLE_INTERVAL_MS / 1000.0))
    }

    pub fn with_interval(mut source: Box<dyn ConditionSource>, interval: Duration) -> Sampler {
        let limits = source.limits();
        let (commands, rx) = mpsc::channel();
        let (tx, windows) = mpsc::channel();
        let steps = Arc::new(AtomicU32::new(0));
        let clock = Arc::new(AtomicU64::new(f64::NAN.to_bits()));
        let live = Live {
            steps: Arc::clone(&steps),
            clock: Arc::clone(&clock),
        };
        let thread = std::thread::Builder::new()
            .name("tessera-conditions".into())
            .spawn(move || run(source.as_mut(), interval, &rx, &tx, &live))
            .ok();
        Sampler {
            commands: Some(commands),
            windows,
            thread,
            limits,
            steps,
            clock,
        }
    }

    pub fn limits(&self) -> &DeviceLimits {
        &self.limits
    }

    /// Opens a window: the thread samples now and then periodically. Does not wait.
    pub fn begin(&self) {
        self.steps.store(0, Ordering::Release);
        self.clock.store(f64::NAN.to_bits(), Ordering::Release);
        if let Some(c) = &self.commands {
            let _ = c.send(Command::Begin(None));
        }
    }

    /// [`Sampler::begin`] with its own period for this window (the energy window samples every
    /// millisecond to place the energy counter's steps).
    pub fn begin_every(&self, interval: Duration) {
        self.steps.store(0, Ordering::Release);
        self.clock.store(f64::NAN.to_bits(), Ordering::Release);
        if let Some(c) = &self.commands {
            let _ = c.send(Command::Begin(Some(interval)));
        }
    }

    /// How many times the energy counter has changed between the samples of the open window so
    /// far (0 before the thread has sampled, and without an energy counter).
    pub fn energy_steps(&self) -> u32 {
        self.steps.load(Ordering::Acquire)
    }

    /// The graphics clock of the open window's latest sample, in MHz (`None` before the thread
    /// has sampled it, or where the source reads no clock).
    pub fn latest_clock_mhz(&self) -> Option<f64> {
        let v = f64::from_bits(self.clock.load(Ordering::Acquire));
        (!v.is_nan()).then_some(v)
    }

    /// Closes the window after one last sample and returns its samples (empty when no window
    /// was open or the thread could not start).
    pub fn end(&self) -> Vec<Sample> {
        match &self.commands {
            Some(c) if c.send(Command::End).is_ok() => self.windows.recv().unwrap_or_default(),
            _ => Vec::new(),
        }
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // Closing the channel ends the thread.
        self.commands = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// What the sampling thread shares while a window is open.
struct Live {
    steps: Arc<AtomicU32>,
    clock: Arc<AtomicU64>,
}

fn run(
    source: &mut dyn ConditionSource,
    interval: Duration,
    commands: &Receiver<Command>,
    windows: &Sender<Vec<Sample>>,
    live: &Live,
) {
    let take = |source: &mut dyn ConditionSource, t0: Instant| {
        let mut s = source.sample();
        s.at_s = t0.elapsed().as_secs_f64();
        if let Some(mhz) = s.graphics_clock_mhz {
            live.clock.store(mhz.to_bits(), Ordering::Release);
        }
        s
    };
    // The open window: its start, its samples, when the next periodic sample is due, its period.
    let mut window: Option<(Instant, Vec<Sample>, Instant, Duration)> = None;
    loop {
        let command = match &window {
            None => commands.recv().map_err(|_| RecvTimeoutError::Disconnected),
            Some((_, _, next, _)) => {
                commands.recv_timeout(next.saturating_duration_since(Instant::now()))
            }
        };
        match command {
            Err(RecvTimeoutError::Disconnected) => return,
            Err(RecvTimeoutError::Timeout) => {
                if let Some((t0, samples, next, period)) = &mut window {
                    let sample = take(source, *t0);
                    let before = samples.last().and_then(|s| s.energy_mj);
                    if sample.energy_mj.is_some() && before.is_some() && sample.energy_mj != before
                    {
                        live.steps.fetch_add(1, Ordering::Release);
                    }
                    samples.push(sample);
                    *next += *period;
                }
            }
            // A second begin restarts the window.
            Ok(Command::Begin(period)) => {
                let period = period.unwrap_or(interval);
                live.steps.store(0, Ordering::Release);
                let t0 = Instant::now();
                let first = take(source, t0);
                window = Some((t0, vec![first], t0 + period, period));
            }
            Ok(Command::End) => {
                let samples = match window.take() {
                    Some((t0, mut samples, _, _)) => {
                        samples.push(take(source, t0));
                        samples
                    }
                    None => Vec::new(),
                };
                let _ = windows.send(samples);
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A source that counts its reads: clock 1000 + read number, energy 10 mJ more each read.
    pub struct Counting(pub u32);

    impl ConditionSource for Counting {
        fn limits(&self) -> DeviceLimits {
            DeviceLimits {
                source: "fake",
                device: "counting".into(),
                max_graphics_clock_mhz: Some(2000.0),
                max_memory_clock_mhz: None,
                energy_counter: true,
            }
        }
        fn sample(&mut self) -> Sample {
            self.0 += 1;
            Sample {
                graphics_clock_mhz: Some(1000.0 + f64::from(self.0)),
                energy_mj: Some(10.0 * f64::from(self.0)),
                ..Sample::default()
            }
        }
    }

    #[test]
    fn a_window_has_a_sample_at_each_end_in_time_order() {
        // A period far longer than the test: only the two end samples are taken.
        let s = Sampler::with_interval(Box::new(Counting(0)), Duration::from_secs(3600));
        assert_eq!(s.limits().device, "counting");
        assert!(s.end().is_empty(), "no window open");
        s.begin();
        let w = s.end();
        assert_eq!(w.len(), 2);
        assert_eq!(w[0].graphics_clock_mhz, Some(1001.0));
        assert_eq!(w[1].graphics_clock_mhz, Some(1002.0));
        assert!(w[0].at_s <= w[1].at_s);
        // The next window starts afresh from the same source.
        s.begin();
        let w = s.end();
        assert_eq!(w.len(), 2);
        assert_eq!(w[0].energy_mj, Some(30.0));
    }

    #[test]
    fn a_window_can_take_its_own_period() {
        // The sampler's period is an hour; this window's a millisecond.
        let s = Sampler::with_interval(Box::new(Counting(0)), Duration::from_secs(3600));
        s.begin_every(Duration::from_millis(1));
        std::thread::sleep(Duration::from_millis(30));
        let w = s.end();
        assert!(w.len() > 2, "{} samples", w.len());
        // The next plain window is back to the sampler's period: its two ends only.
        s.begin();
        assert_eq!(s.end().len(), 2);
    }

    #[test]
    fn periodic_samples_between_the_ends() {
        let s = Sampler::with_interval(Box::new(Counting(0)), Duration::from_millis(1));
        s.begin();
        std::thread::sleep(Duration::from_millis(30));
        let w = s.end();
        assert!(w.len() > 2, "{} samples", w.len());
        assert!(w.windows(2).all(|p| p[0].at_s <= p[1].at_s));
    }

    #[test]
    fn energy_steps_count_the_counters_changes_in_the_open_window() {
        // Counting's energy changes on every read: each periodic sample is a step.
        let s = Sampler::with_interval(Box::new(Counting(0)), Duration::from_millis(1));
        assert_eq!(s.energy_steps(), 0);
        s.begin();
        let t = Instant::now();
        while s.energy_steps() < 3 && t.elapsed() < Duration::from_secs(10) {
            std::thread::sleep(Duration::from_millis(1));
        }
        let steps = s.energy_steps();
        let w = s.end();
        assert!(steps >= 3, "{steps} steps");
        // Every periodic sample changed the counter; the first and the closing one are not
        // counted as steps by the time `steps` was read.
        assert!(
            w.len() as u32 >= steps + 2,
            "{} samples, {steps} steps",
            w.len()
        );
        // A new window starts from zero at once.
        s.begin_every(Duration::from_secs(3600));
        assert_eq!(s.energy_steps(), 0);
        let _ = s.end();
    }
}
