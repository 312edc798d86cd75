//! Interface types shared by the contact solvers: the condensed problem, the
//! friction models, the solution, the errors and an independent KKT check.
//!
//! Layout of every 3n vector (`b`, `r`, `u`) and of the rows/columns of `W`:
//! point i owns entries `3i` (t1), `3i + 1` (t2), `3i + 2` (n), in the point's
//! [`LocalFrame`](super::frame::LocalFrame).
//!
//! Sign convention (it makes W = C K⁻¹ Cᵀ positive semidefinite):
//! * `C` maps the global displacement to the relative displacement of side B
//!   with respect to side A in the local frames, so `(C u)_n` is the gap
//!   increment (positive = opening).
//! * `r` is the contact force **acting on side B** in the local frame; side A
//!   receives `−r`; the global nodal force is `Cᵀ r`. A compressive contact
//!   pushes B away from A, so `r_n ≥ 0` and `r_n` opens the gap: W_nn > 0.
//! * `u = b + W r` is the relative displacement with the contact forces:
//!   `u_n` is the gap (≥ 0 when admissible), `u_t` the tangential slip
//!   increment of B with respect to A.
//! * Friction opposes slip: a sliding point has `r_t = −μ_k r_n u_t/‖u_t‖`.

use crate::vocab::Invalid;
use nalgebra::DMatrix;
use thiserror::Error;

/// Friction law of one contact point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionModel {
    /// No tangential force: `r_t = 0`.
    Frictionless,
    /// Tangentially stuck whatever the forces: `u_t = 0`, `r_t` free
    /// (a shear key / fully bonded tangential direction). The normal stays
    /// unilateral.
    Tied,
    /// Coulomb friction with a static coefficient (stick test) and a kinetic
    /// coefficient (sliding bound), `0 ≤ mu_k ≤ mu_s`.
    Coulomb { mu_s: f64, mu_k: f64 },
}

impl FrictionModel {
    /// Coulomb friction with equal static and kinetic coefficients.
    pub fn coulomb(mu: f64) -> Self {
        FrictionModel::Coulomb { mu_s: mu, mu_k: mu }
    }

    /// `Err` names the offending coefficient.
    pub fn validate(&self) -> Result<(), Invalid> {
        if let FrictionModel::Coulomb { mu_s, mu_k } = *self {
            if !(mu_s.is_finite() && mu_s >= 0.0) {
                return Err(Invalid::new(
                    "mu_s",
                    format!("mu_s must be finite and >= 0, got {mu_s}"),
                ));
            }
            if !(mu_k.is_finite() && mu_k >= 0.0) {
                return Err(Invalid::new(
                    "mu_k",
                    format!("mu_k must be finite and >= 0, got {mu_k}"),
                ));
            }
            if mu_k > mu_s {
                return Err(Invalid::new(
                    "mu_k",
                    format!("mu_k must be <= mu_s, got mu_k = {mu_k} > mu_s = {mu_s}"),
                ));
            }
        }
        Ok(())
    }
}

/// State of a contact point after the solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContactState {
    /// No normal force (`r_n = 0`); the gap may be open or exactly closed.
    /// Coulomb and frictionless points then carry no tangential force either.
    Open,
    /// Closed and tangentially stuck: `u_t = 0`, `‖r_t‖` below its bound
    /// (always the case for [`FrictionModel::Tied`]).
    Stick,
    /// Closed with the tangential force on its bound `μ_k r_n` (Coulomb) or 0
    /// (frictionless): the point slides.
    Slip,
}

impl ContactState {
    /// Stick or Slip.
    pub fn is_closed(self) -> bool {
        !matches!(self, ContactState::Open)
    }
}

/// The condensed contact problem of one step (3n rows, see the module doc).
#[derive(Debug, Clone, Copy)]
pub struct ContactProblem<'a> {
    /// Delassus operator W = C K⁻¹ Cᵀ (3n × 3n, symmetric PSD): relative
    /// displacement of B w.r.t. A per unit contact force on B.
    pub w: &'a DMatrix<f64>,
    /// Free relative displacement (3n): `b_n` = gap without contact forces
    /// this step (g0 + normal displacement; ≥ 0 open), `b_t` = tangential
    /// increment without contact forces.
    pub b: &'a [f64],
    /// Friction model per point (n entries).
    pub friction: &'a [FrictionModel],
}

impl<'a> ContactProblem<'a> {
    pub fn new(w: &'a DMatrix<f64>, b: &'a [f64], friction: &'a [FrictionModel]) -> Self {
        Self { w, b, friction }
    }

    /// Number of contact points.
    pub fn n_points(&self) -> usize {
        self.friction.len()
    }

    /// Dimensions, finiteness, friction coefficients, non-negative diagonal
    /// and symmetry of W to `symmetry_tolerance` × max|W_ij|.
    pub fn validate(&self, symmetry_tolerance: f64) -> Result<(), ContactError> {
        let m = 3 * self.friction.len();
        check_dims("b", self.b.len(), m)?;
        validate_operator(self.w, self.b, symmetry_tolerance)?;
        for (i, f) in self.friction.iter().enumerate() {
            f.validate()
                .map_err(|e| ContactError::Invalid(format!("friction of point {i}: {e}")))?;
        }
        Ok(())
    }
}

/// Normal-only problem: W_nn (n × n) and the free gaps (n). Used when every
/// point is frictionless or the driver condenses only the normal rows.
#[derive(Debug, Clone, Copy)]
pub struct NormalProblem<'a> {
    /// Normal block of the Delassus operator (n × n, symmetric PSD).
    pub w: &'a DMatrix<f64>,
    /// Free gaps (n), ≥ 0 open.
    pub gap: &'a [f64],
}

impl<'a> NormalProblem<'a> {
    pub fn new(w: &'a DMatrix<f64>, gap: &'a [f64]) -> Self {
        Self { w, gap }
    }

    /// Dimensions, finiteness, non-negative diagonal and symmetry of W.
    pub fn validate(&self, symmetry_tolerance: f64) -> Result<(), ContactError> {
        validate_operator(self.w, self.gap, symmetry_tolerance)
    }
}

/// Errors of the contact solvers.
#[derive(Debug, Error)]
pub enum ContactError {
    #[error("contact problem: {what} has dimension {found}, expected {expected}")]
    Dimension {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    #[error("contact problem: {0}")]
    Invalid(String),
    #[error("contact settings: {0}")]
    Settings(String),
    #[error(
        "contact: the cone solver (clarabel) stopped with status {status} \
         in friction fixed-point iteration {iteration}"
    )]
    Solver { status: String, iteration: usize },
    #[error(
        "contact: the friction fixed point did not converge in {iterations} iterations \
         (last relative change of the slip bounds {change:.3e})"
    )]
    NotConverged { iterations: usize, change: f64 },
    #[error("contact: relative KKT residual {residual:.3e} of the solution exceeds the limit {limit:.3e}")]
    Kkt { residual: f64, limit: f64 },
}

/// Reference magnitudes that make every tolerance relative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scales {
    /// max |b| (falls back to max |u|, then 1, when b = 0).
    pub displacement: f64,
    /// Mean diagonal of W (compliance per unit force).
    pub compliance: f64,
    /// displacement / compliance: the force that closes the largest free
    /// displacement through the mean compliance.
    pub force: f64,
}

/// KKT residual of a contact solution, every entry relative: displacements
/// divided by [`Scales::displacement`], forces by [`Scales::force`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct KktResidual {
    /// max over points of max(0, −u_n): penetration.
    pub penetration: f64,
    /// max over points of max(0, −r_n): tension across the joint.
    pub tension: f64,
    /// max over points of min(r_n⁺, u_n⁺): a closed point must have no gap,
    /// an open one no force.
    pub complementarity: f64,
    /// Friction law. Frictionless: ‖r_t‖. Tied: ‖u_t‖. Coulomb: the smaller
    /// of the stick residual max(‖u_t‖, ‖r_t‖ − μ_s r_n⁺) and the slip
    /// residual ‖r_t + μ_k r_n⁺ u_t/‖u_t‖‖.
    pub friction: f64,
}

impl KktResidual {
    /// The largest component.
    pub fn max(&self) -> f64 {
        self.penetration
            .max(self.tension)
            .max(self.complementarity)
            .max(self.friction)
    }
}

/// Result of a contact solve, all vectors in the layout of the problem: 3
/// rows a point for a [`ContactProblem`], one (the normal) for a
/// [`NormalProblem`], whose closed points are in state `Slip`.
#[derive(Debug, Clone)]
pub struct ContactSolution {
    /// Contact forces on side B, local frames (N).
    pub r: Vec<f64>,
    /// Relative displacement with the forces, `u = b + W r`: u_n = gap (m),
    /// u_t = tangential slip increment.
    pub u: Vec<f64>,
    /// Per point.
    pub states: Vec<ContactState>,
    /// Cone programs solved (friction fixed-point iterations, all rounds).
    pub fixed_point_iterations: usize,
    /// Interior-point iterations summed over the cone programs.
    pub ipm_iterations: usize,
    /// Wall time in clarabel (setup + solve of every cone program), s.
    pub cone_seconds: f64,
    /// Wall time in the polish (Newton / active-set rounds), s.
    pub polish_seconds: f64,
    /// `kkt.max()`, relative.
    pub kkt_residual: f64,
    /// The KKT residual by component, recomputed from `r` and `u`.
    pub kkt: KktResidual,
    /// The reference magnitudes the relative tolerances refer to.
    pub scales: Scales,
}

impl ContactSolution {
    /// Per point: does it carry force (stick or slip)?
    pub fn closed(&self) -> Vec<bool> {
        self.states.iter().map(|s| s.is_closed()).collect()
    }
}

/// Rows of one point in a problem's vectors, and its friction law.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PointRows {
    pub n: usize,
    pub t: Option<[usize; 2]>,
    pub model: FrictionModel,
}

pub(crate) fn point_rows_3d(friction: &[FrictionModel]) -> Vec<PointRows> {
    friction
        .iter()
        .enumerate()
        .map(|(i, &model)| PointRows {
            n: 3 * i + 2,
            t: Some([3 * i, 3 * i + 1]),
            model,
        })
        .collect()
}

pub(crate) fn point_rows_normal(n: usize) -> Vec<PointRows> {
    (0..n)
        .map(|i| PointRows {
            n: i,
            t: None,
            model: FrictionModel::Frictionless,
        })
        .collect()
}

pub(crate) fn check_dims(
    what: &'static str,
    found: usize,
    expected: usize,
) -> Result<(), ContactError> {
    if found != expected {
        return Err(ContactError::Dimension {
            what,
            expected,
            found,
        });
    }
    Ok(())
}

fn validate_operator(
    w: &DMatrix<f64>,
    b: &[f64],
    symmetry_tolerance: f64,
) -> Result<(), ContactError> {
    let m = b.len();
    check_dims("W rows", w.nrows(), m)?;
    check_dims("W columns", w.ncols(), m)?;
    if let Some(k) = b.iter().position(|v| !v.is_finite()) {
        return Err(ContactError::Invalid(format!(
            "free displacement b[{k}] is not finite ({})",
            b[k]
        )));
    }
    let mut wmax = 0.0f64;
    for j in 0..m {
        for i in 0..m {
            let v = w[(i, j)];
            if !v.is_finite() {
                return Err(ContactError::Invalid(format!(
                    "W[{i}, {j}] is not finite ({v})"
                )));
            }
            wmax = wmax.max(v.abs());
        }
    }
    for i in 0..m {
        if w[(i, i)] < 0.0 {
            return Err(ContactError::Invalid(format!(
                "W[{i}, {i}] = {} < 0: W must be positive semidefinite",
                w[(i, i)]
            )));
        }
    }
    if m > 0 && mean_diagonal(w) <= 0.0 {
        return Err(ContactError::Invalid(
            "W has a zero diagonal: the contact points are rigidly held".into(),
        ));
    }
    let limit = symmetry_tolerance * wmax;
    for j in 0..m {
        for i in 0..j {
            let d = (w[(i, j)] - w[(j, i)]).abs();
            if d > limit {
                return Err(ContactError::Invalid(format!(
                    "W is not symmetric: |W[{i}, {j}] − W[{j}, {i}]| = {d:.3e} > {limit:.3e}"
                )));
            }
        }
    }
    Ok(())
}

pub(crate) fn mean_diagonal(w: &DMatrix<f64>) -> f64 {
    let m = w.nrows().min(w.ncols());
    if m == 0 {
        return 1.0;
    }
    (0..m).map(|i| w[(i, i)]).sum::<f64>() / m as f64
}

pub(crate) fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// `u = b + W r` (W applied as given, not symmetrised).
pub(crate) fn apply(w: &DMatrix<f64>, b: &[f64], r: &[f64]) -> Vec<f64> {
    let mut u = b.to_vec();
    let m = b.len();
    for (j, &rj) in r.iter().enumerate().take(m) {
        if rj == 0.0 {
            continue;
        }
        let col = w.column(j);
        for (ui, wij) in u.iter_mut().zip(col.iter()) {
            *ui += wij * rj;
        }
    }
    u
}

pub(crate) fn scales_of(w: &DMatrix<f64>, b: &[f64], u: Option<&[f64]>) -> Scales {
    let compliance = mean_diagonal(w);
    let mut displacement = max_abs(b);
    if displacement == 0.0 {
        displacement = u.map(max_abs).unwrap_or(0.0);
    }
    if displacement == 0.0 || !displacement.is_finite() {
        displacement = 1.0;
    }
    Scales {
        displacement,
        compliance,
        force: displacement / compliance,
    }
}

fn norm2(a: f64, b: f64) -> f64 {
    a.hypot(b)
}

/// Relative KKT residual of `(r, u)` for the given points (see [`KktResidual`]).
pub(crate) fn kkt_of(points: &[PointRows], r: &[f64], u: &[f64], sc: &Scales) -> KktResidual {
    let fs = 1.0 / sc.force;
    let ds = 1.0 / sc.displacement;
    let mut k = KktResidual::default();
    for p in points {
        let rn = r[p.n] * fs;
        let un = u[p.n] * ds;
        k.penetration = k.penetration.max((-un).max(0.0));
        k.tension = k.tension.max((-rn).max(0.0));
        k.complementarity = k.complementarity.max(rn.max(0.0).min(un.max(0.0)));
        let Some([t1, t2]) = p.t else { continue };
        let (rt1, rt2) = (r[t1] * fs, r[t2] * fs);
        let (ut1, ut2) = (u[t1] * ds, u[t2] * ds);
        let rt = norm2(rt1, rt2);
        let ut = norm2(ut1, ut2);
        let f = match p.model {
            FrictionModel::Frictionless => rt,
            FrictionModel::Tied => ut,
            FrictionModel::Coulomb { mu_s, mu_k } => {
                let rnp = rn.max(0.0);
                let stick = ut.max(rt - mu_s * rnp);
                let slip = if ut > 0.0 {
                    let bound = mu_k * rnp / ut;
                    norm2(rt1 + bound * ut1, rt2 + bound * ut2)
                } else {
                    (rt - mu_k * rnp).abs()
                };
                stick.min(slip)
            }
        };
        k.friction = k.friction.max(f);
    }
    k
}

/// Independent KKT check of contact forces `r` (3n) for a problem: computes
/// `u = b + W r` and returns the relative residual and the scales used.
pub fn kkt_residual(
    problem: &ContactProblem,
    r: &[f64],
) -> Result<(KktResidual, Scales), ContactError> {
    let m = 3 * problem.n_points();
    check_dims("b", problem.b.len(), m)?;
    check_dims("W rows", problem.w.nrows(), m)?;
    check_dims("W columns", problem.w.ncols(), m)?;
    check_dims("r", r.len(), m)?;
    let u = apply(problem.w, problem.b, r);
    let sc = scales_of(problem.w, problem.b, Some(&u));
    let points = point_rows_3d(problem.friction);
    Ok((kkt_of(&points, r, &u, &sc), sc))
}

/// Independent KKT check of normal forces `r_n` (n) for a normal-only problem.
pub fn normal_kkt_residual(
    problem: &NormalProblem,
    r_n: &[f64],
) -> Result<(KktResidual, Scales), ContactError> {
    let m = problem.gap.len();
    check_dims("W rows", problem.w.nrows(), m)?;
    check_dims("W columns", problem.w.ncols(), m)?;
    check_dims("r_n", r_n.len(), m)?;
    let u = apply(problem.w, problem.gap, r_n);
    let sc = scales_of(problem.w, problem.gap, Some(&u));
    let points = point_rows_normal(m);
    Ok((kkt_of(&points, r_n, &u, &sc), sc))
}
