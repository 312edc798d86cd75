//! Concrete ageing laws and Zhu Bofang's pipe-cooling functions.
//!
//! Everything here is a pure function of concrete age or stage time; the
//! thermal module turns these into per-step source increments.

pub mod adiabatic;
pub mod pipe_cooling;

pub use adiabatic::AdiabaticRise;
pub use pipe_cooling::{PipeLayout, ZhuPipe};
