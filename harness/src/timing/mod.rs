//! Pure figures over the per-frame times a variant's timed frames produced: when to stop
//! sampling under `measured = "auto"` ([`stop`]) and how even the frames were ([`pacing`]).
//! No GPU, no clocks: the render loop feeds them samples.

pub mod pacing;
pub mod stop;
