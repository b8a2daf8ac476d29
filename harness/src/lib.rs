//! Tessera's harness: scenarios in, timed GPU frames and result files out.
//!
//! The binary (`main.rs`) is a thin command-line layer over this library so that tests can drive
//! the same code paths.

pub mod compare;
pub mod conditions;
pub mod expect;
pub mod files;
pub mod gpu;
pub mod metric;
pub mod metrics_device;
pub mod params;
pub mod regimes;
pub mod render;
pub mod run;
pub mod runner;
pub mod scenario;
pub mod tables;
pub mod techniques;
pub mod timing;
pub mod upload;
pub mod world;
