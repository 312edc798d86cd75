//! Files of a run folder. A run folder is built in a hidden staging folder
//! next to its destination and renamed into place only when complete, so an
//! interrupted or failed run never leaves half a result behind. Its
//! destination is replaced whole, so a run folder is marked as one
//! ([`run_dir::MARKER`]), keeps the engineer's what-ifs across runs, and is
//! locked while written ([`lock`]): a weekly job on a shared drive must
//! never destroy what it did not write.

pub mod apertures;
pub mod lock;
pub mod run_dir;
pub mod snapshot;
pub mod temperatures;

pub use lock::RunLock;
pub use run_dir::RunDir;
