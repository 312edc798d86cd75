//! The complete dam loaded at once (every lift born, every joint closed,
//! self-weight): the hard contact step of `groutready study perf`, with its
//! counters and the joint states it ends in; `--passes` prints its contact
//! passes one by one (`mechanics::contact_step::PassRecord`).
//!
//!     cargo run --release --example complete_step [SCENE] [--passes]

use groutready::mechanics::contact_step::PassRecord;

/// The binary's allocator (huge pages for the large factors), so that the
/// step is timed as `groutready` runs it: with the system's allocator the
/// first factor's 1.4 GB of L took 3.7 s to allocate on the large arch.
#[global_allocator]
static ALLOCATOR: groutready::machine::LargeBlocksOnHugePages =
    groutready::machine::LargeBlocksOnHugePages;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let passes = args.iter().any(|a| a == "--passes");
    let path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let cost = groutready::study::full_dam_mechanics_step_cost(&inputs.scene, &inputs.mesh)?;
    if passes {
        print_passes(&cost.passes);
    }
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
    println!(
        "analysis {:.1} s (ordering {:.1} s), rock condensed {:.1} s, rock solves {:.1} s, assembly {:.1} s, joints {:.1} s",
        s.seconds_symbolic,
        s.seconds_ordering,
        s.seconds_condensation,
        s.seconds_rock,
        s.seconds_assembly,
        s.seconds_joints
    );
    Ok(())
}

/// One line per contact pass.
fn print_passes(passes: &[PassRecord]) {
    println!("pass  kind        changes   open  stick   slip  factor   rank coupled  slip residual  wrong");
    for (i, p) in passes.iter().enumerate() {
        println!(
            "{:4}  {:<10} {:8} {:6} {:6} {:6}  {:6} {:6} {:7}  {:13.3e}  {}",
            i + 1,
            format!("{:?}", p.kind),
            p.changes,
            p.open,
            p.stick,
            p.slip,
            if p.factorised { "yes" } else { "" },
            p.rank,
            p.couplings,
            p.slip_residual,
            p.wrong_normal.map_or(String::new(), |w| w.to_string()),
        );
    }
}
