//! Every integration test in one binary: one link of the crate and its
//! dependencies instead of one per file (the build time of CI).

// Component loops (`for c in 0..3`) read as the formulas they check.
#![allow(clippy::needless_range_loop)]

/// The in-process runs allocate as the binary does (large blocks on huge
/// pages), so the tests exercise its allocator too.
#[global_allocator]
static ALLOCATOR: groutready::machine::LargeBlocksOnHugePages =
    groutready::machine::LargeBlocksOnHugePages;

mod common;

mod arch_table;
mod cli_plan;
mod cli_run;
mod contact_qp;
mod contact_solvers_agree;
mod damaged_restart;
mod demo_plan;
mod far_boundary;
mod fast_path;
mod fem_elasticity;
mod fem_elements;
mod fem_sparse;
mod hard_cases;
mod joint_friction;
mod joint_grout_stops;
mod joint_grouting;
mod joint_two_blocks;
mod layer_merging;
mod material_creep;
mod material_laws;
mod mechanics_staged;
mod mesh_files;
mod mesh_generators;
mod mesh_import;
mod mesh_scenes;
mod out_safety;
mod planner_limits;
mod planner_search_steps;
mod planner_supercool;
mod planner_together;
mod report_files;
mod reproducible;
mod restart;
mod rock_ties;
mod scene_errors;
mod schedule_errors;
mod study_accuracy;
mod study_compare;
mod thermal_closed_forms;
mod tui_screens;
mod tui_tmux;
