//! Ageing of concrete: elastic modulus E(τ) and autogenous deformation G(τ).
