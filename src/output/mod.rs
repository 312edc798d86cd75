//! Files of a run folder. A run folder is built in a hidden staging folder
//! next to its destination and renamed into place only when complete, so an
//! interrupted or failed run never leaves half a result behind.

pub mod apertures;
pub mod run_dir;
pub mod snapshot;
pub mod temperatures;

pub use run_dir::RunDir;
