//! Transverse joints: contact before grouting, thin bonded layer after.
//!
//! # Contact before grouting: the condensed problem
//!
//! The staged driver condenses each step's joint problem onto the n live
//! contact points. Point i has a local frame (t1, t2, n) ([`LocalFrame`],
//! n from side A to side B) and the unknown contact force r_i = (r_t1, r_t2,
//! r_n) **acting on side B** (side A gets −r_i; the global nodal force is
//! Cᵀ r). With C the map from global displacements to the relative
//! displacement of B w.r.t. A in the local frames:
//!
//! ```text
//! W = C K⁻¹ Cᵀ   (3n × 3n, symmetric PSD),   b = g0·e_n + C K⁻¹ f   (free relative displacement)
//! u = b + W r    (relative displacement with the contact forces; u_n = gap)
//! ```
//!
//! A compressive force r_n ≥ 0 pushes the sides apart (W_nn > 0).
//! Conditions per point:
//! * normal (Signorini): u_n ≥ 0, r_n ≥ 0, u_n r_n = 0 — no penetration, no
//!   tension across an ungrouted joint;
//! * Coulomb friction: stick ‖r_t‖ ≤ μ_s r_n with u_t = 0, or slip
//!   r_t = −μ_k r_n u_t/‖u_t‖ (maximum dissipation, friction opposes slip);
//!   [`FrictionModel::Frictionless`]: r_t = 0; [`FrictionModel::Tied`]: u_t = 0.
//!
//! # The cone program (`qp`)
//!
//! With slip bounds s_i fixed (Tresca), the conditions are exactly the KKT
//! conditions of the convex program
//!
//! ```text
//! min ½ rᵀ W r + bᵀ r   s.t.  r_n,i ≥ 0,   ‖r_t,i‖ ≤ s_i
//! ```
//!
//! (gradient = u; −u in the normal cone of the constraint set gives u_n ≥ 0
//! with complementarity and u_t = −λ r_t, λ ≥ 0, on the bound). [`qp::solve`]
//! hands it to clarabel — a nonnegative cone for the normals, a second-order
//! cone (s_i, r_t1, r_t2) per Coulomb point, free tangential variables for tied
//! points, no tangential variables for frictionless points — after scaling W by
//! its mean diagonal ω and b by β = max|b| (units drop out). Coulomb friction is
//! the fixed point s_i ← μ r_n,i (static coefficient first, kinetic for the
//! points that reach their static bound; see [`qp`]). The interior-point answer
//! is then polished: Newton's method on the equalities of its open/stick/slip
//! states, with state switches where an inequality fails, takes it to round-off
//! (the interior point alone resolves slip directions to ~1e-6).
//! [`qp::solve_normal`] is the plain QP on the normal rows only.
//!
//! Static/kinetic friction makes stick and slip both admissible for
//! μ_k r_n ≤ ‖r_t‖ ≤ μ_s r_n; the solver prefers stick: a point slides only
//! when it cannot stick with μ_s, and then with μ_k.
//!
//! # Verification
//!
//! Every solution is checked independently of clarabel ([`kkt_residual`]):
//! u = b + W r is recomputed and the relative residuals of penetration,
//! tension, complementarity and the friction law (the smaller of the stick and
//! the slip residual of each point) must stay below
//! [`ContactSettings::kkt_tolerance`]; the residual is returned in the
//! solution (the solver calls the same check before returning). Relative
//! means: displacements over max|b|, forces over max|b|/mean(diag W).
//! `tests/it/contact_qp.rs` holds the closed forms: a single point (open, closed,
//! tied); two bars between walls (aperture g0 − αΔT·L when cooled,
//! σ = −E(αΔT·L − g0)/L when heated past closure, from W = C K⁻¹ Cᵀ of a spring
//! chain); a sliding block at μ = 0, μ_s/μ_k = 0.4/0.3 and 5/4 (stick with
//! r_t = −T below μ_s N, slip with |r_t| = μ_k N above) and with
//! normal–tangential coupling; the limit push on an inclined plane
//! (F/G = (tanα + μ)/(1 − μ tanα) = 0.412371 by bisection) and a coupled
//! 4-point patch reaching it together; unit invariance (m/N vs mm/MN, mm/N,
//! km/kN to 1e-9); seeded random problems (50–200 points, mixed
//! open/stick/slip) with KKT ≤ 1e-8, warm starts and the unpolished fixed
//! point agreeing.

pub mod contact;
pub mod frame;
pub mod qp;

pub use contact::{
    kkt_residual, normal_kkt_residual, ContactError, ContactProblem, ContactSolution, ContactState,
    FrictionModel, KktResidual, NormalProblem, Scales,
};
pub use frame::LocalFrame;
pub use qp::{solve, solve_normal, ContactSettings};
