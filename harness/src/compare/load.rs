//! Reading a run folder back, for `tessera compare` (typed records) and `tessera upload` (the
//! JSON, upgraded to the current schema version): both through `tessera_results::folder`, the
//! reader the dashboard's import uses too, so the three accept and refuse the same folders. Not
//! for: writing runs (see [`crate::run::output`]).

pub use tessera_results::folder::{
    read as load_run, read_raw, RawRun, ReadError as LoadError, Run,
};
