//! groutready: staged 3-D finite-element simulation of concrete arch dams under
//! construction, answering per grouting zone whether a transverse joint will be
//! open enough to grout on its planned date.
//!
//! The pipeline shows in the module tree:
//! scene + schedule → mesh → fem (element → quadrature → assembly → solve)
//! → thermal → sim (staged driver) → output. See `docs/ARCHITECTURE.md`.

pub mod app;
pub mod fem;
pub mod joint;
pub mod machine;
pub mod material;
pub mod mechanics;
pub mod mesh;
pub mod output;
pub mod planner;
pub mod progress;
pub mod report;
pub mod scene;
pub mod schedule;
pub mod sim;
pub mod study;
pub mod thermal;
pub mod tui;
pub mod vocab;
