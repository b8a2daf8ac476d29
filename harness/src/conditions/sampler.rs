//! The sampling thread: owns a [`ConditionSource`] and reads it while a window is open, so that no
//! sensor read sits on the thread that submits and collects frames.
//!
//! [`Sampler::begin`] is a channel send (the render loop calls it as the last warm-up frame
//! completes); the thread then samples at once and every [`SAMPLE_INTERVAL_MS`] until
//! [`Sampler::end`], which takes one last sample and returns the window's samples. Between windows
//! the thread sleeps on its channel.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
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
        let thread = std::thread::Builder::new()
            .name("tessera-conditions".into())
            .spawn(move || run(source.as_mut(), interval, &rx, &tx))
            .ok();
        Sampler {
            commands: Some(commands),
            windows,
            thread,
            limits,
        }
    }

    pub fn limits(&self) -> &DeviceLimits {
        &self.limits
    }

    /// Opens a window: the thread samples now and then periodically. Does not wait.
    pub fn begin(&self) {
        if let Some(c) = &self.commands {
            let _ = c.send(Command::Begin(None));
        }
    }

    /// [`Sampler::begin`] with its own period for this window (the energy window samples every
    /// millisecond to place the energy counter's steps).
    pub fn begin_every(&self, interval: Duration) {
        if let Some(c) = &self.commands {
            let _ = c.send(Command::Begin(Some(interval)));
        }
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

fn run(
    source: &mut dyn ConditionSource,
    interval: Duration,
    commands: &Receiver<Command>,
    windows: &Sender<Vec<Sample>>,
) {
    let take = |source: &mut dyn ConditionSource, t0: Instant| {
        let mut s = source.sample();
        s.at_s = t0.elapsed().as_secs_f64();
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
                    samples.push(take(source, *t0));
                    *next += *period;
                }
            }
            // A second begin restarts the window.
            Ok(Command::Begin(period)) => {
                let period = period.unwrap_or(interval);
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
}
