//! Zhu Bofang's equivalent (homogenised) pipe-cooling method.
//!
//! # Equations
//!
//! A coil of length L \[m\] with water flow q_w embedded at spacings S1 × S2
//! cools an equivalent cylinder of diameter D = 1.167 √(S1 S2) (radius
//! b = D/2). Its mean temperature, with water at T_w and initial mean T0,
//! is T̄ = T_w + (T0 − T_w) φ(t) + H(t) with
//!
//! * φ(t) = exp(−p t^s), t in days since the stage started;
//! * p = k (a′/D²)^s, a′ the (corrected, see below) diffusivity in m²/day;
//! * k = 2.08 − 1.174 ξ + 0.256 ξ², s = 0.971 + 0.1485 ξ − 0.0445 ξ²;
//! * ξ = λ L / (c_w ρ_w q_w), λ the concrete conductivity [W/(m K)],
//!   c_w [J/(kg K)], ρ_w \[kg/m³\], q_w \[m³/s\]: dimensionless, it measures how
//!   much the water warms along the coil;
//! * H(t) = ∫₀ᵗ φ(t − u) θ′(τ_k + u) du, the hydration heat that stays in
//!   the concrete while the pipes run (θ0 ψ(t) of Zhu when τ_k = 0), where
//!   τ_k is the concrete age when the stage started.
//!
//! # Pipe material and pipe radius
//!
//! Zhu's k and s were fitted for a metal pipe with b/c = 100 (c = outer
//! pipe radius). Zhu treats other ratios and plastic (HDPE) pipes in
//! "Effect of cooling by water flowing in nonmetal pipes embedded in mass
//! concrete", J. Constr. Eng. Manage. 125(1), 1999, pp. 61–68. We could not
//! retrieve that paper's formulas to check them, so the correction below is
//! derived here from first principles; it should be compared with the
//! paper before it is trusted for design.
//!
//! 1. The pipe wall (r0 … c, conductivity λ1) is replaced by concrete of the
//!    same steady radial thermal resistance, which turns the pipe into a
//!    metal pipe of smaller radius c1:
//!    ln(c/c1)/λ = ln(c/r0)/λ1, so c1 = c·exp(−(λ/λ1)·ln(c/r0)).
//!    The heat capacity of the fictitious concrete shell c1 … c is
//!    negligible (its area is a few 1e-4 of the cylinder's). For steel
//!    (λ1 ≈ 45) c1 ≈ c.
//! 2. The metal-pipe cylinder (T = 0 at r = c1, ∂T/∂r = 0 at r = b) decays
//!    at late times as exp(−a α1² t), α1 the first root of
//!    J1(α b) Y0(α c1) − Y1(α b) J0(α c1) = 0. α1 b depends only on b/c1;
//!    for b/c = 100 it is 0.716 690 632 469. We keep Zhu's fit and
//!    substitute a′ = a · (α1b(b/c1) / α1b(100))², which reproduces the
//!    leading decay rate of the actual geometry and leaves Zhu's formula
//!    untouched at b/c1 = 100.
//!
//! Consistency check of the anchor: with ξ = 0 (no water warming) the
//! leading mode gives φ ≈ exp(−(2 α1 b)² a t/D²) with (2·0.7167)² = 2.055,
//! against Zhu's k(0) = 2.08, s(0) = 0.971 (his fit also absorbs the higher
//! modes); the test suite asserts this agreement to 2 %.
//!
//! α1 b is found by scanning for the first sign change and bisecting, with
//! power-series J0, J1, Y0, Y1 (arguments stay below ~12 for any layout that
//! passes [`PipeLayout::validate`]; the series then keeps ~13 digits).
//!
//! # Quadrature of H
//!
//! With the hydration variable y (θ = θ0(1 − e^{−y}): y = mτ, aτ^b, or
//! ln(1 + τ/n) for the three forms) the Stieltjes integral becomes
//! H = θ0 e^{−y0} ∫₀^Y e^{−η} φ(V) dη, η = y − y(τ_k), Y = y(τ_k + t) − y(τ_k),
//! with V = t − u the time left, written through δ = Y − η in closed form
//! (exponential V = δ/m; compound V = −τ1·expm1(ln1p(−δ/y1)/b), or
//! t − (τ(y) − τ_k) in the half near τ_k; hyperbolic V = −(n + τ1)·expm1(−δ)),
//! so neither end loses digits to cancellation. The substitution removes the
//! τ^{b−1} singularity of the compound rate and the algebraic tail of the
//! hyperbolic rate, and makes e^{−y0} (second-stage cooling at large τ_k) an
//! exact factor. What is left, handled by composite 16-point Gauss–Legendre:
//!
//! * the integrand is exp(−η − pV^s), two monotone terms of opposite sign:
//!   panels are cut where either term has changed by 16 (a 16-point rule
//!   integrates an exponential of that total variation to ~1e-13);
//! * V^s branches at δ = 0 (s ≠ 1): the last panel, where both terms change
//!   by at most 1, uses δ = h w^q with q = ⌈7/(1 + s)⌉ (4 for s in
//!   [0.8, 1.2]; the singular terms become w^{q(1+s)−1}, exponent ≥ 6), and
//!   the panels before it grow ×4;
//! * for the compound form τ(y) = (y/a)^{1/b} branches at y = 0 (η = −y0):
//!   panels grow ×4 from it and, when it is closer than half the first
//!   panel, that panel uses y = y_b w^q with q = ⌈7b/(1 + b)⌉. Each end
//!   panel is kept short enough that the other end's branch point stays at
//!   w ≥ √2;
//! * the range where exp(−η − pV^s) is below e^{−42} of the larger end value
//!   is dropped (the neglected mass is bounded by e^{−42} times that value),
//!   so long stages cost no more than short ones.
//!
//! Typical cost 2–8 µs per call (≈ 50–250 integrand evaluations); corners
//! where H < 1e−100 °C take up to ~35 µs.
//!
//! Verified in `tests/it/material_laws.rs`: against the closed form
//! θ0 m e^{−mτ_k}(e^{−pt} − e^{−mt})/(m − p) for s = 1 (≤ 1e-12 asserted),
//! against 24 mpmath references at 40 digits (≤ 1e-12 asserted), and against
//! an independent brute-force quadrature on 576 combinations of form, s in
//! [0.8, 1.2], τ_k and t up to 400 days (≤ 1e-10 asserted). Measured during
//! development on 392 random cases: ≤ 8e-14 from the brute force and ≤ 4e-14
//! from the mpmath references wherever those two agree with each other.

// `!(x > 0.0)` is the comparison that also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::vocab::Invalid;
use serde::{Deserialize, Serialize};

use super::adiabatic::AdiabaticRise;
use super::positive;

/// Geometry and hydraulics of one embedded cooling-pipe layout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipeLayout {
    /// Horizontal pipe spacing S1 \[m\].
    pub spacing_horizontal_m: f64,
    /// Vertical pipe spacing S2 \[m\] (usually the lift height or half of it).
    pub spacing_vertical_m: f64,
    /// Length L of one pipe coil \[m\].
    pub length_m: f64,
    /// Water flow q_w [L/min].
    pub flow_l_per_min: f64,
    /// Outer pipe radius c \[m\].
    pub outer_radius_m: f64,
    /// Inner pipe radius r0 \[m\].
    pub inner_radius_m: f64,
    /// Conductivity of the pipe wall λ1 [W/(m K)]: HDPE ≈ 0.4–1.7, steel ≈ 45.
    pub wall_conductivity_w_mk: f64,
    /// Water density \[kg/m³\], default 1000.
    #[serde(default = "default_water_density")]
    pub water_density: f64,
    /// Water specific heat [J/(kg K)], default 4186.
    #[serde(default = "default_water_specific_heat")]
    pub water_specific_heat: f64,
}

fn default_water_density() -> f64 {
    1000.0
}
fn default_water_specific_heat() -> f64 {
    4186.0
}

impl PipeLayout {
    /// Checks the layout; the error names the offending field, e.g.
    /// `length_m must be > 0, got 0`.
    pub fn validate(&self) -> Result<(), Invalid> {
        positive("spacing_horizontal_m", self.spacing_horizontal_m)?;
        positive("spacing_vertical_m", self.spacing_vertical_m)?;
        positive("length_m", self.length_m)?;
        positive("flow_l_per_min", self.flow_l_per_min)?;
        positive("outer_radius_m", self.outer_radius_m)?;
        let half = 0.5 * self.spacing_horizontal_m.min(self.spacing_vertical_m);
        if !(self.outer_radius_m < half) {
            return Err(Invalid::new(
                "outer_radius_m",
                format!(
                    "outer_radius_m must be < half the smaller spacing ({half}), got {}",
                    self.outer_radius_m
                ),
            ));
        }
        positive("inner_radius_m", self.inner_radius_m)?;
        if !(self.inner_radius_m < self.outer_radius_m) {
            return Err(Invalid::new(
                "inner_radius_m",
                format!(
                    "inner_radius_m must be < outer_radius_m ({}), got {}",
                    self.outer_radius_m, self.inner_radius_m
                ),
            ));
        }
        positive("wall_conductivity_w_mk", self.wall_conductivity_w_mk)?;
        positive("water_density", self.water_density)?;
        positive("water_specific_heat", self.water_specific_heat)?;
        Ok(())
    }

    /// Water flow in m³/s.
    pub fn flow_m3_per_s(&self) -> f64 {
        self.flow_l_per_min / 1000.0 / 60.0
    }

    /// Diameter D = 1.167 √(S1 S2) of Zhu's equivalent cooling cylinder \[m\].
    pub fn cylinder_diameter_m(&self) -> f64 {
        1.167 * (self.spacing_horizontal_m * self.spacing_vertical_m).sqrt()
    }
}

/// ξ = λ L / (c_w ρ_w q_w) (dimensionless), λ = concrete conductivity in
/// W/(m K), q_w converted from L/min to m³/s.
pub fn dimensionless_xi(layout: &PipeLayout, conductivity_w_mk: f64) -> f64 {
    conductivity_w_mk * layout.length_m
        / (layout.water_specific_heat * layout.water_density * layout.flow_m3_per_s())
}

/// Zhu's fitted (k, s) for a given ξ.
pub fn zhu_k_s(xi: f64) -> (f64, f64) {
    (
        2.08 - 1.174 * xi + 0.256 * xi * xi,
        0.971 + 0.1485 * xi - 0.0445 * xi * xi,
    )
}

/// α1 b at Zhu's reference ratio b/c = 100 (30-digit value from mpmath).
#[allow(clippy::excessive_precision)]
pub const ALPHA1_B_AT_100: f64 = 0.716_690_632_468_996_2;

/// Every intermediate quantity of [`ZhuPipe::new`], for reports and tests.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ZhuDerivation {
    /// ξ = λ L / (c_w ρ_w q_w).
    pub xi: f64,
    /// k(ξ).
    pub k: f64,
    /// s(ξ).
    pub s: f64,
    /// D = 1.167 √(S1 S2) \[m\].
    pub diameter_m: f64,
    /// Equivalent metal-pipe radius c1 = c exp(−(λ/λ1) ln(c/r0)) \[m\].
    pub equivalent_radius_m: f64,
    /// b / c1 with b = D/2.
    pub b_over_c1: f64,
    /// First eigenvalue α1 b of the cylinder for b/c1.
    pub alpha1_b: f64,
    /// a′ = a (α1 b / 0.71669)² \[m²/day\].
    pub equivalent_diffusivity_m2_per_day: f64,
    /// p = k (a′/D²)^s \[1/day^s\].
    pub p: f64,
}

/// φ(t) = exp(−p t^s) of the equivalent cooling cylinder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ZhuPipe {
    pub p: f64,
    pub s: f64,
}

impl ZhuPipe {
    /// Zhu's φ for `layout` in a concrete of diffusivity a \[m²/day\] and
    /// conductivity λ [W/(m K)], corrected for the pipe radius and wall (see
    /// the module doc). Inputs are assumed valid (see [`ZhuPipe::try_new`]);
    /// invalid inputs give NaN or meaningless values, never a panic.
    pub fn new(layout: &PipeLayout, diffusivity_m2_per_day: f64, conductivity_w_mk: f64) -> Self {
        let d = Self::derive(layout, diffusivity_m2_per_day, conductivity_w_mk);
        ZhuPipe { p: d.p, s: d.s }
    }

    /// [`ZhuPipe::new`] after checking the layout, the concrete properties
    /// and that ξ stays where s(ξ) ≥ 0.8 (ξ ≤ 4.24): beyond it the quadratic
    /// fit is far from the range it was made for and
    /// [`hydration_under_cooling`] is not verified.
    pub fn try_new(
        layout: &PipeLayout,
        diffusivity_m2_per_day: f64,
        conductivity_w_mk: f64,
    ) -> Result<Self, Invalid> {
        layout.validate()?;
        positive("diffusivity_m2_per_day", diffusivity_m2_per_day)?;
        positive("conductivity_w_mk", conductivity_w_mk)?;
        let d = Self::derive(layout, diffusivity_m2_per_day, conductivity_w_mk);
        if !(d.s >= 0.8) {
            return Err(Invalid::new("xi", format!("xi = conductivity·length_m/(water_specific_heat·water_density·flow) must be <= 4.24 \
                 (Zhu's fit gives s < 0.8 beyond), got {}; shorten the coil or raise the flow",
                d.xi
            )));
        }
        if !(d.p > 0.0 && d.p.is_finite()) {
            return Err(Invalid::new(
                "p",
                format!("pipe cooling: p must be > 0, got {}", d.p),
            ));
        }
        Ok(ZhuPipe { p: d.p, s: d.s })
    }

    /// All intermediate quantities of [`ZhuPipe::new`].
    pub fn derive(
        layout: &PipeLayout,
        diffusivity_m2_per_day: f64,
        conductivity_w_mk: f64,
    ) -> ZhuDerivation {
        let xi = dimensionless_xi(layout, conductivity_w_mk);
        let (k, s) = zhu_k_s(xi);
        let diameter = layout.cylinder_diameter_m();
        let c = layout.outer_radius_m;
        let c1 = c
            * (-(conductivity_w_mk / layout.wall_conductivity_w_mk)
                * (c / layout.inner_radius_m).ln())
            .exp();
        let b_over_c1 = 0.5 * diameter / c1;
        let alpha1_b = first_eigenvalue_alpha_b(b_over_c1);
        let ratio = alpha1_b / ALPHA1_B_AT_100;
        let a_eq = diffusivity_m2_per_day * ratio * ratio;
        let p = k * (a_eq / (diameter * diameter)).powf(s);
        ZhuDerivation {
            xi,
            k,
            s,
            diameter_m: diameter,
            equivalent_radius_m: c1,
            b_over_c1,
            alpha1_b,
            equivalent_diffusivity_m2_per_day: a_eq,
            p,
        }
    }

    /// φ(t) = exp(−p t^s); 1 for t ≤ 0.
    pub fn phi(&self, t_days: f64) -> f64 {
        if t_days <= 0.0 {
            return 1.0;
        }
        (-self.p * t_days.powf(self.s)).exp()
    }
}

/// First root α1 b of J1(αb) Y0(αc) − Y1(αb) J0(αc) = 0 for the ratio
/// r = b/c > 1 (cylinder c ≤ r ≤ b, T = 0 at c, insulated at b). NaN when no
/// root is found (r ≤ 1, or r so close to 1 that α1 b > 60).
pub fn first_eigenvalue_alpha_b(b_over_c: f64) -> f64 {
    let r = b_over_c;
    if !(r > 1.0) || !r.is_finite() {
        return f64::NAN;
    }
    let g = |x: f64| {
        let xc = x / r;
        bessel::j1(x) * bessel::y0(xc) - bessel::y1(x) * bessel::j0(xc)
    };
    // g > 0 near 0 (−Y1 ~ 2/(πx) dominates); roots are ≥ π apart in x, so a
    // 5 % step below x = 60 cannot step over two of them.
    let mut lo = 1e-3;
    let mut g_lo = g(lo);
    let mut hi = lo;
    let mut found = false;
    while hi < 60.0 {
        hi = lo * 1.05;
        let g_hi = g(hi);
        if g_lo > 0.0 && g_hi <= 0.0 {
            found = true;
            break;
        }
        lo = hi;
        g_lo = g_hi;
    }
    if !found {
        return f64::NAN;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Power series of J0, J1, Y0, Y1 (Abramowitz & Stegun 9.1.10, 9.1.11,
/// 9.1.13). Good to ~1e-13 absolute for x ≲ 12, which covers every valid
/// layout; callers never pass x ≤ 0.
mod bessel {
    const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;
    const MAX_TERMS: usize = 400;
    use std::f64::consts::PI;

    /// Σ (−q)^k/(k!)² and Σ (−q)^k H_k/(k!)², q = x²/4.
    fn series0(x: f64) -> (f64, f64) {
        let q = 0.25 * x * x;
        let (mut term, mut sum, mut hsum, mut h) = (1.0, 1.0, 0.0, 0.0);
        for k in 1..MAX_TERMS {
            let kf = k as f64;
            term *= -q / (kf * kf);
            h += 1.0 / kf;
            sum += term;
            hsum += term * h;
            if term.abs() < 1e-18 * sum.abs().max(1e-300) && kf > q.sqrt() {
                break;
            }
        }
        (sum, hsum)
    }

    /// (J1(x), Σ (−q)^k [ψ(k+1) + ψ(k+2)] (x/2)^{2k+1}/(k!(k+1)!)).
    fn series1(x: f64) -> (f64, f64) {
        let q = 0.25 * x * x;
        let half = 0.5 * x;
        let mut term = half; // (x/2)^{2k+1}/(k!(k+1)!) with sign, k = 0
        let mut psi_k1 = -EULER_GAMMA; // ψ(1)
        let mut psi_k2 = 1.0 - EULER_GAMMA; // ψ(2)
        let mut sum = term;
        let mut psum = term * (psi_k1 + psi_k2);
        for k in 1..MAX_TERMS {
            let kf = k as f64;
            term *= -q / (kf * (kf + 1.0));
            psi_k1 += 1.0 / kf;
            psi_k2 += 1.0 / (kf + 1.0);
            sum += term;
            psum += term * (psi_k1 + psi_k2);
            if term.abs() < 1e-18 * sum.abs().max(1e-300) && kf > q.sqrt() {
                break;
            }
        }
        (sum, psum)
    }

    pub fn j0(x: f64) -> f64 {
        series0(x).0
    }

    pub fn j1(x: f64) -> f64 {
        series1(x).0
    }

    pub fn y0(x: f64) -> f64 {
        let (j, h) = series0(x);
        // A&S 9.1.13: Y0 = (2/π)[(ln(x/2) + γ) J0 + Σ_{k≥1} (−1)^{k+1} H_k q^k/(k!)²].
        2.0 / PI * (((0.5 * x).ln() + EULER_GAMMA) * j - h)
    }

    pub fn y1(x: f64) -> f64 {
        let (j, p) = series1(x);
        2.0 / PI * (0.5 * x).ln() * j - 2.0 / (PI * x) - p / PI
    }
}

/// 16-point Gauss–Legendre on [−1, 1]: (node, weight) for the positive
/// nodes (30-digit values from mpmath, rounded).
#[allow(clippy::excessive_precision)]
const GL16: [(f64, f64); 8] = [
    (0.989_400_934_991_649_932_6, 0.027_152_459_411_754_094_85),
    (0.944_575_023_073_232_576_1, 0.062_253_523_938_647_892_86),
    (0.865_631_202_387_831_743_9, 0.095_158_511_682_492_784_81),
    (0.755_404_408_355_003_033_9, 0.124_628_971_255_533_872_1),
    (0.617_876_244_402_643_748_4, 0.149_595_988_816_576_732_1),
    (0.458_016_777_657_227_386_3, 0.169_156_519_395_002_538_2),
    (0.281_603_550_779_258_913_2, 0.182_603_415_044_923_588_9),
    (0.095_012_509_837_637_440_19, 0.189_450_610_455_068_496_3),
];

/// Parts of the integrand exp(−η − pV^s) below e^{−CUT} of the larger end
/// value are dropped: e^{−42} ≈ 6e-19.
const CUT: f64 = 42.0;
/// Largest change of either monotone term (η or pV^s) inside one panel.
const PANEL_VAR: f64 = 16.0;
/// Same for the end panel at V → 0, which carries δ = h w^q: the power
/// magnifies the growth of the integrand off the real axis, so these panels
/// stay short (a variation of 2 already cost ~1e-13).
const END_VAR: f64 = 1.0;
/// Same for the compound form's end panel at τ_k, which carries y = y_b w^q.
const LEFT_END_VAR: f64 = 1.0;
/// Growth ratio of panels away from a branch point.
const GRADE: f64 = 4.0;

/// V(δ) = time left (days) at hydration distance δ = Y − η from the end of
/// the stage, and its inverse.
#[derive(Clone, Copy)]
enum TimeLeft {
    Exponential {
        m: f64,
    },
    Compound {
        a: f64,
        b: f64,
        t: f64,
        tau_k: f64,
        tau1: f64,
        y0: f64,
        y1: f64,
        half_y: f64,
    },
    Hyperbolic {
        n_plus_tau1: f64,
    },
}

impl TimeLeft {
    /// V at a point given by both coordinates (η, δ = Y − η).
    #[inline]
    fn v(self, eta: f64, delta: f64) -> f64 {
        match self {
            TimeLeft::Exponential { m } => delta / m,
            TimeLeft::Compound {
                a,
                b,
                t,
                tau_k,
                tau1,
                y0,
                y1,
                half_y,
            } => {
                if delta > half_y {
                    // Near τ_k, 1 − δ/y1 would lose the digits of η/y1.
                    let elapsed = if tau_k > 0.0 {
                        tau_k * ((eta / y0).ln_1p() / b).exp_m1()
                    } else {
                        (eta / a).powf(1.0 / b)
                    };
                    t - elapsed
                } else {
                    -tau1 * ((-delta / y1).ln_1p() / b).exp_m1()
                }
            }
            TimeLeft::Hyperbolic { n_plus_tau1 } => -n_plus_tau1 * (-delta).exp_m1(),
        }
    }

    fn delta(self, v: f64) -> f64 {
        match self {
            TimeLeft::Exponential { m } => m * v,
            TimeLeft::Compound { b, tau1, y1, .. } => -y1 * (b * (-v / tau1).ln_1p()).exp_m1(),
            TimeLeft::Hyperbolic { n_plus_tau1 } => -(-v / n_plus_tau1).ln_1p(),
        }
    }
}

/// A panel boundary: η from the stage start and δ = Y − η from its end, each
/// computed from the end it is close to.
#[derive(Clone, Copy, Debug)]
struct Point {
    eta: f64,
    delta: f64,
}

/// `b` lies strictly after `a`, compared in the coordinate of the nearer
/// end (the other one may round to a tie).
fn advances(a: Point, b: Point) -> bool {
    if a.delta.min(b.delta) < a.eta.min(b.eta) {
        b.delta < a.delta
    } else {
        b.eta > a.eta
    }
}

/// Two boundaries within 1e-9 (relative, in the coordinate of the nearer
/// end) of each other.
fn close(a: Point, b: Point) -> bool {
    let (x, y) = if a.delta.min(b.delta) < a.eta.min(b.eta) {
        (a.delta, b.delta)
    } else {
        (a.eta, b.eta)
    };
    (x - y).abs() <= 1e-9 * x.abs().max(y.abs())
}

/// The hydration part of T̄ while pipes run, in °C:
/// H(t) = ∫₀ᵗ φ(t − u) θ′(τ_k + u) du, τ_k = `stage_start_age` (days),
/// t = `t_days` since the stage started. θ0 ψ(t) of Zhu when τ_k = 0.
///
/// 0 for t ≤ 0; a stage that starts before the pour (τ_k < 0) only
/// convolves the rise after the pour. NaN for NaN input, an invalid rise, or
/// a pipe with p < 0 or s ≤ 0. Accurate to ~1e-13 relative for s in
/// [0.8, 1.2] (see the module doc), a few µs per call.
pub fn hydration_under_cooling(
    pipe: &ZhuPipe,
    rise: &AdiabaticRise,
    stage_start_age: f64,
    t_days: f64,
) -> f64 {
    let (p, s) = (pipe.p, pipe.s);
    if t_days.is_nan() || stage_start_age.is_nan() || !(p >= 0.0) || !(s > 0.0) {
        return f64::NAN;
    }
    if !p.is_finite() || !s.is_finite() || !rise.is_valid() {
        return f64::NAN;
    }
    let (mut tau_k, mut t) = (stage_start_age, t_days);
    if tau_k < 0.0 {
        // Only the part of the stage after the pour sees any rise.
        t += tau_k;
        tau_k = 0.0;
    }
    if !(t > 0.0) {
        return 0.0;
    }
    let tau1 = tau_k + t;
    if !tau1.is_finite() {
        return f64::NAN;
    }
    let (theta0, f) = Integrand::new(p, s, rise, tau_k, t, tau1);
    let big_y = f.big_y;
    if !(big_y > 0.0) || !big_y.is_finite() {
        // Y underflows only when H is below ~1e-300 θ0.
        return if big_y == 0.0 { 0.0 } else { f64::NAN };
    }
    let Some((start, end)) = f.kept_range(t) else {
        // The kept range underflowed (p ~ 1e20): nothing measurable is left.
        return 0.0;
    };
    let q_left = match *rise {
        AdiabaticRise::Compound { b, .. } => (7.0 * b / (1.0 + b)).ceil().clamp(1.0, 12.0) as i32,
        _ => 1,
    };
    theta0 * f.integrate(&f.panels(start, end, q_left))
}

/// exp(−y0 − η − pV^s), the integrand of H/θ0 in the hydration variable
/// (module doc, "Quadrature of H"), with what its panels are cut by.
#[derive(Clone, Copy)]
struct Integrand {
    p: f64,
    s: f64,
    /// Hydration variable at the stage start.
    y0: f64,
    /// Growth Y of the hydration variable over the stage.
    big_y: f64,
    map: TimeLeft,
    /// The compound form: τ(y) = (y/a)^{1/b} branches at y = 0 (η = −y0).
    branches: bool,
}

/// Panel boundaries from the start to the end of the kept range, and the
/// substitution powers of the end panels that carry a branch point.
struct Panels {
    kept: Vec<Point>,
    /// The last panel reaches V = 0 and carries δ = h w^q_right.
    right_singular: bool,
    q_right: i32,
    /// The first panel is near the compound form's branch point and carries
    /// y = y_b w^q_left.
    left_singular: bool,
    q_left: i32,
}

impl Integrand {
    /// Step 1, the substitution: the hydration variable of the rise's form
    /// at the stage start (y0), its growth over the stage (Y) and the time
    /// left V(δ); returns θ0 alongside.
    fn new(p: f64, s: f64, rise: &AdiabaticRise, tau_k: f64, t: f64, tau1: f64) -> (f64, Self) {
        let (theta0, y0, big_y, map, branches) = match *rise {
            AdiabaticRise::Exponential { theta0, m } => {
                (theta0, m * tau_k, m * t, TimeLeft::Exponential { m }, false)
            }
            AdiabaticRise::Compound { theta0, a, b } => {
                let y1 = a * tau1.powf(b);
                let (y0, big_y) = if tau_k > 0.0 {
                    let y0 = a * tau_k.powf(b);
                    (y0, y0 * (b * (t / tau_k).ln_1p()).exp_m1())
                } else {
                    (0.0, y1)
                };
                // τ(y) = (y/a)^{1/b} branches at y = 0, i.e. η = −y0.
                (
                    theta0,
                    y0,
                    big_y,
                    TimeLeft::Compound {
                        a,
                        b,
                        t,
                        tau_k,
                        tau1,
                        y0,
                        y1,
                        half_y: 0.5 * big_y,
                    },
                    true,
                )
            }
            AdiabaticRise::Hyperbolic { theta0, n } => (
                theta0,
                (tau_k / n).ln_1p(),
                (t / (n + tau_k)).ln_1p(),
                TimeLeft::Hyperbolic {
                    n_plus_tau1: n + tau1,
                },
                false,
            ),
        };
        let f = Integrand {
            p,
            s,
            y0,
            big_y,
            map,
            branches,
        };
        (theta0, f)
    }

    /// pV^s at a point given by both coordinates.
    fn p_v_s(&self, eta: f64, delta: f64) -> f64 {
        if self.p == 0.0 {
            0.0
        } else {
            self.p * self.map.v(eta, delta).powf(self.s)
        }
    }

    /// V where pV^s = `level`.
    fn v_of_level(&self, level: f64) -> f64 {
        (level / self.p).powf(1.0 / self.s)
    }

    fn f(&self, eta: f64, delta: f64) -> f64 {
        (-self.y0 - eta - self.p_v_s(eta, delta)).exp()
    }

    fn at_eta(&self, eta: f64) -> Point {
        Point {
            eta,
            delta: self.big_y - eta,
        }
    }

    fn at_delta(&self, delta: f64) -> Point {
        Point {
            eta: self.big_y - delta,
            delta,
        }
    }

    /// Step 2, the cut: the range kept from the stage of length `t`, `None`
    /// when nothing of it is left. log f = −η − pV^s; the tail η > η_hi has
    /// f ≤ e^{−η} and the head where pV^s > lim has f ≤ e^{−lim − η}: each
    /// drops at most e^{g_ref − CUT}, while the kept end contributes
    /// ~e^{g_ref}.
    fn kept_range(&self, t: f64) -> Option<(Point, Point)> {
        let (p, s, big_y) = (self.p, self.s, self.big_y);
        let g_start = -p * t.powf(s);
        let g_ref = g_start.max(-big_y);
        let lim = CUT - g_ref;
        let (eta_hi, delta_hi) = if big_y > lim {
            (lim, big_y - lim)
        } else {
            (big_y, 0.0)
        };
        let (eta_lo, delta_lo) = if -g_start > lim {
            let d = self.map.delta(self.v_of_level(lim)).min(big_y);
            (big_y - d, d)
        } else {
            (0.0, big_y)
        };
        if !(delta_lo > delta_hi) {
            return None;
        }
        let start = Point {
            eta: eta_lo,
            delta: delta_lo,
        };
        let end = Point {
            eta: eta_hi,
            delta: delta_hi,
        };
        Some((start, end))
    }

    /// Step 3, the panels: boundaries where either monotone term has changed
    /// by `PANEL_VAR`, the graded end panels at the branch points, then the
    /// strictly advancing sequence of them from `start` to `end`.
    fn panels(&self, start: Point, end: Point, q_left: i32) -> Panels {
        let p = self.p;
        let mut pts: Vec<Point> = Vec::with_capacity(32);
        // Uniform in η: bounds the change of e^{−η}.
        let mut eta = start.eta + PANEL_VAR;
        while eta < end.eta {
            pts.push(self.at_eta(eta));
            eta += PANEL_VAR;
        }
        // Uniform in pV^s: bounds the change of φ.
        let level_lo = self.p_v_s(start.eta, start.delta);
        let level_hi = self.p_v_s(end.eta, end.delta);
        if p > 0.0 {
            let mut level = (level_hi / PANEL_VAR).floor() * PANEL_VAR + PANEL_VAR;
            while level < level_lo {
                pts.push(self.at_delta(self.map.delta(self.v_of_level(level))));
                level += PANEL_VAR;
            }
        }
        // Substitution powers of the end panels: the branch terms V^s ~ δ^s and
        // (y/a)^{1/b} become w^{q(s+1)−1} and w^{q(1/b+1)−1}; exponents ≥ 6
        // leave Gauss–Legendre errors ~16^{−14}, and the smallest such q keeps
        // the smooth part of low degree in w (a larger q spreads it over
        // w^{q/b}, w^{qs}, … and costs digits).
        let q_right = (7.0 / (1.0 + self.s)).ceil().clamp(1.0, 12.0) as i32;
        let right_singular = end.delta == 0.0;
        let d_end = if right_singular {
            self.right_end(&mut pts, start, level_lo, q_right as f64)
        } else {
            0.0
        };
        let left = if self.branches && start.eta == 0.0 {
            Some(self.left_end(&mut pts, end, level_lo, q_left as f64, right_singular))
        } else {
            None
        };
        let (left_singular, e_end) = left.unwrap_or((false, 0.0));
        // Near the right end η = Y − δ can tie for distinct δ: break ties on δ.
        pts.sort_by(|a, b| a.eta.total_cmp(&b.eta).then(b.delta.total_cmp(&a.delta)));
        // A strictly advancing sequence; nothing inside the substituted end
        // panels (a sliver left there by rounding would put the branch point at
        // the end of a plain Gauss panel); no slivers, which only cost time.
        let mut kept: Vec<Point> = Vec::with_capacity(pts.len() + 3);
        kept.push(start);
        for q in pts {
            let last = kept[kept.len() - 1];
            let inside_right = right_singular && q.delta < d_end * (1.0 - 1e-9);
            let inside_left = left_singular && q.eta < e_end * (1.0 - 1e-9);
            if inside_right
                || inside_left
                || !advances(last, q)
                || !advances(q, end)
                || close(last, q)
                || close(q, end)
            {
                continue;
            }
            kept.push(q);
        }
        kept.push(end);
        if kept.len() == 2 && left_singular && right_singular {
            // One panel cannot carry both substitutions.
            kept.insert(1, self.at_eta(0.5 * (start.eta + end.eta)));
        }
        Panels {
            kept,
            right_singular,
            q_right,
            left_singular,
            q_left,
        }
    }

    /// Right end (V → 0, branch point of V^s when s ≠ 1): an end panel
    /// [0, d_end] in δ, then panels growing geometrically from it; returns
    /// d_end. A substitution w^q pulls the other end's branch point towards
    /// the panel: keep it at w ≥ √2 (Bernstein ellipse ρ > 3.3 for [0, 1]).
    fn right_end(&self, pts: &mut Vec<Point>, start: Point, level_lo: f64, qr: f64) -> f64 {
        let delta_lo = start.delta;
        let mut d_end = END_VAR.min(delta_lo);
        if self.p > 0.0 && END_VAR < level_lo {
            d_end = d_end.min(self.map.delta(self.v_of_level(END_VAR)));
        }
        if self.branches {
            d_end = d_end.min((self.big_y + self.y0) / 2f64.powf(0.5 * qr));
        }
        let mut d = d_end;
        while d > 0.0 && d < delta_lo {
            pts.push(self.at_delta(d));
            d *= GRADE;
        }
        d_end
    }

    /// Compound form at the stage start: branch point of τ(y) at η = −y0, an
    /// end panel [0, e_end] in η, then panels growing geometrically from the
    /// branch point; returns whether the first panel needs the substitution,
    /// and e_end.
    fn left_end(
        &self,
        pts: &mut Vec<Point>,
        end: Point,
        level_lo: f64,
        ql: f64,
        right_singular: bool,
    ) -> (bool, f64) {
        let (big_y, y0, eta_hi) = (self.big_y, self.y0, end.eta);
        let mut e_end = LEFT_END_VAR.min(eta_hi);
        if self.p > 0.0 && level_lo > LEFT_END_VAR {
            e_end = e_end.min(big_y - self.map.delta(self.v_of_level(level_lo - LEFT_END_VAR)));
        }
        if right_singular {
            let room = (big_y + y0) / 2f64.powf(0.5 * ql) - y0;
            e_end = e_end.min(room.max(0.0));
        }
        let left_singular = y0 < 0.5 * e_end;
        // Distance from the branch point is y = y0 + η.
        let mut y = y0 + e_end;
        while y > 0.0 && y - y0 < eta_hi {
            pts.push(self.at_eta(y - y0));
            y *= GRADE;
        }
        (left_singular, e_end)
    }

    /// Step 4, the quadrature: 16-point Gauss–Legendre on every panel, the
    /// substituted end panels in w; one running sum over all panels. Returns
    /// H/θ0.
    fn integrate(&self, panels: &Panels) -> f64 {
        let big_y = self.big_y;
        let y0 = self.y0;
        let (qr, ql) = (panels.q_right as f64, panels.q_left as f64);
        let mut sum = 0.0;
        let last = panels.kept.len() - 2;
        for (i, w) in panels.kept.windows(2).enumerate() {
            let (a, b) = (w[0], w[1]);
            if i == last && panels.right_singular {
                // δ = h w^q on w ∈ [0, 1].
                let h = a.delta;
                for &(x, wt) in GL16.iter() {
                    for xs in [x, -x] {
                        let u = 0.5 * (1.0 + xs);
                        let uq1 = u.powi(panels.q_right - 1);
                        let delta = h * uq1 * u;
                        sum += wt * 0.5 * qr * h * uq1 * self.f(big_y - delta, delta);
                    }
                }
            } else if i == 0 && panels.left_singular {
                // y = y_b w^q on w ∈ [w_lo, 1], y = y0 + η.
                let yb = y0 + b.eta;
                let w_lo = (y0 / yb).powf(1.0 / ql);
                let half = 0.5 * (1.0 - w_lo);
                for &(x, wt) in GL16.iter() {
                    for xs in [x, -x] {
                        let u = w_lo + half * (1.0 + xs);
                        let uq1 = u.powi(panels.q_left - 1);
                        let eta = (yb * uq1 * u - y0).max(0.0);
                        sum += wt * half * ql * yb * uq1 * self.f(eta, big_y - eta);
                    }
                }
            } else {
                let half = if a.delta < a.eta {
                    0.5 * (a.delta - b.delta)
                } else {
                    0.5 * (b.eta - a.eta)
                };
                for &(x, wt) in GL16.iter() {
                    for xs in [x, -x] {
                        sum += wt
                            * half
                            * self.f(a.eta + half * (1.0 + xs), b.delta + half * (1.0 - xs));
                    }
                }
            }
        }
        sum
    }
}
