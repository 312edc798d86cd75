//! groutready: staged 3-D finite-element simulation of concrete arch dams under
//! construction, answering per grouting zone whether a transverse joint will be
//! open enough to grout on its planned date.
//!
//! The pipeline shows in the module tree:
//! scene + schedule → mesh → fem (element → quadrature → assembly → solve)
//! → thermal → sim (staged driver) → output. See `docs/ARCHITECTURE.md`.

// The module docs are written for the people who carry the code on, and
// name the private items that do the work: read them with
// `cargo doc --document-private-items`, where those links resolve.
#![allow(rustdoc::private_intra_doc_links)]

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
