//! What the measuring examples share: a scene's inputs from the command line.

use groutready::app::{self, Inputs};

/// The inputs of the scene named by the first argument (the demo by
/// default), its path, and its rock's modulus \[Pa\] (20 GPa where the scene
/// gives none): the examples' matrices take mature concrete and this rock.
pub fn scene_from_args() -> anyhow::Result<(String, Inputs, f64)> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = app::load_inputs(std::path::Path::new(&path), None)?;
    let rock_e = inputs
        .scene
        .rock
        .as_ref()
        .and_then(|r| r.modulus_pa)
        .unwrap_or(2e10);
    Ok((path, inputs, rock_e))
}
