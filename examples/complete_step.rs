//! The complete dam loaded at once (every lift born, every joint closed,
//! self-weight): the hard contact step of `groutready study perf`, with its
//! counters and the joint states it ends in.
//!
//!     cargo run --release --example complete_step [SCENE]

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let cost = groutready::study::full_dam_mechanics_step_cost(&inputs.scene, &inputs.mesh)?;
    let s = &cost.stats;
    println!(
        "{} dofs, {} pairs: step {:.2} s, {} numeric factorisations, {} passes ({} of them moving slip forces only), largest tension kept closed {:.3e} Pa",
        s.max_dofs,
        cost.pairs,
        cost.step_s,
        s.numeric,
        s.contact_iterations,
        s.slip_force_passes,
        s.kept_closed_tension
    );
    let c = &s.capacitance;
    println!(
        "factorisations {:.1} s; corrected solves {} ({:.1} s): {} refinements, {} columns ({:.1} s), \
         {} capacitance LUs ({:.1} s, products {:.1} s, {:.1} Gflop, largest {} rows)",
        s.seconds_numeric,
        c.solves,
        c.seconds,
        c.refinements,
        c.columns,
        c.column_seconds,
        c.s_factorisations,
        c.s_seconds,
        c.product_seconds,
        c.product_flops / 1e9,
        c.max_rank
    );
    Ok(())
}
