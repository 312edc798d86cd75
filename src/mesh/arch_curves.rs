//! The plan curves of an arch's half (crown to one abutment), for the
//! `arch_table` generator ([`super::arch_table`]).
//!
//! # Parametrisation
//!
//! A half-curve starts at the crown, at the origin, tangent to +x, and bends
//! towards +y (downstream). It is parametrised by its **tangent angle**
//! φ ∈ [0, π/2): the tangent there is (cos φ, sin φ), the outward
//! (upstream) normal (sin φ, −cos φ). With ρ(φ) the radius of curvature,
//! dx/dφ = ρ cos φ, dy/dφ = ρ sin φ, ds/dφ = ρ. Every type has ρ(0) = R, the
//! crown radius of the table (`radius_left_m` / `radius_right_m`):
//!
//! * **circular**: ρ = R; x = R sin φ, y = R(1 − cos φ), s = Rφ;
//! * **three-centred**: ρ = R0 = R for φ ≤ φ0 (`central_half_angle_*_deg`),
//!   ρ = R1 (`outer_radius_*_m`) beyond; the circular formulas per piece,
//!   continuous in position and tangent at φ0;
//! * **parabolic**: y = x²/(2R): x = R tan φ, y = R tan²φ / 2,
//!   s = R/2·(tan φ sec φ + ln(sec φ + tan φ)) (ρ = R sec³φ);
//! * **elliptical**: semi-axis a along x, b along y, q = a/b
//!   (`axis_ratio_*`): x = a sin t, y = b(1 − cos t), tan t = q tan φ; the
//!   crown curvature b/a² = 1/R gives a = R/q, b = R/q²; s = ∫₀ᵗ
//!   √(a² cos²τ + b² sin²τ) dτ by composite Simpson (512 panels; the
//!   integrand is smooth, the error is below 1e-12 relative);
//! * **logarithmic spiral**: ρ = R e^{kφ} (k = `spiral_growth_*`; the
//!   Whewell form of r = c·e^{θ cot α}): x = R(e^{kφ}(k cos φ + sin φ) − k)/(1 + k²),
//!   y = R(e^{kφ}(k sin φ − cos φ) + 1)/(1 + k²), s = R(e^{kφ} − 1)/k (Rφ for k = 0).
//!
//! Parametrising by the tangent angle makes "a joint keeps its plan
//! direction at every elevation" a constant φ, and s(φ) is strictly
//! increasing, so [`HalfCurve::angle_at_length`] inverts it by bisection.
//!
//! # Verification
//!
//! `tests/it/arch_table.rs` checks, for every type, that the curve passes
//! through the crown tangent to x and that its finite-difference curvature at
//! the crown is 1/R within 1e-6 relative, that s(φ) agrees with the summed
//! chord lengths, and that the circular type is the parametric arch's ring.

use serde::{Deserialize, Serialize};

/// The arch types of the design tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ArchType {
    Circular,
    #[serde(alias = "three_centered")]
    ThreeCentred,
    Parabolic,
    Elliptical,
    LogSpiral,
}

impl ArchType {
    /// The name in a scene file.
    pub fn name(self) -> &'static str {
        match self {
            ArchType::Circular => "circular",
            ArchType::ThreeCentred => "three_centred",
            ArchType::Parabolic => "parabolic",
            ArchType::Elliptical => "elliptical",
            ArchType::LogSpiral => "log_spiral",
        }
    }
}

/// The coefficients of one half of an arch at one elevation; a type reads
/// only its own (the others are 0).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HalfArch {
    /// Crown radius of curvature R \[m\] (every type).
    pub radius_m: f64,
    /// Three-centred: radius R1 beyond the central arc \[m\].
    pub outer_radius_m: f64,
    /// Three-centred: half-angle φ0 of the central arc \[rad\].
    pub central_half_angle: f64,
    /// Elliptical: semi-axis along x over semi-axis along y.
    pub axis_ratio: f64,
    /// Logarithmic spiral: growth k of ρ = R e^{kφ}.
    pub spiral_growth: f64,
}

impl HalfArch {
    /// (1 − w)·self + w·other, field by field.
    pub fn lerp(&self, other: &HalfArch, w: f64) -> HalfArch {
        let l = |a: f64, b: f64| (1.0 - w) * a + w * b;
        HalfArch {
            radius_m: l(self.radius_m, other.radius_m),
            outer_radius_m: l(self.outer_radius_m, other.outer_radius_m),
            central_half_angle: l(self.central_half_angle, other.central_half_angle),
            axis_ratio: l(self.axis_ratio, other.axis_ratio),
            spiral_growth: l(self.spiral_growth, other.spiral_growth),
        }
    }
}

/// One half of an arch's reference line (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfCurve {
    pub kind: ArchType,
    pub arch: HalfArch,
}

/// Largest tangent angle of a half-curve: just short of a right angle
/// (the parabola and the ellipse reach it only at infinity or at their
/// vertex, and an arch turning further is no arch).
pub const MAX_ANGLE: f64 = 89.0 * std::f64::consts::PI / 180.0;

impl HalfCurve {
    /// The point (x, y) of tangent angle `phi` ∈ [0, π/2), relative to the crown.
    pub fn point(&self, phi: f64) -> [f64; 2] {
        let h = &self.arch;
        let r = h.radius_m;
        match self.kind {
            ArchType::Circular => circle(r, phi),
            ArchType::ThreeCentred => {
                let p0 = h.central_half_angle;
                if phi <= p0 {
                    circle(r, phi)
                } else {
                    let [x0, y0] = circle(r, p0);
                    let r1 = h.outer_radius_m;
                    [
                        x0 + r1 * (phi.sin() - p0.sin()),
                        y0 + r1 * (p0.cos() - phi.cos()),
                    ]
                }
            }
            ArchType::Parabolic => {
                let t = phi.tan();
                [r * t, 0.5 * r * t * t]
            }
            ArchType::Elliptical => {
                let (a, b) = self.semi_axes();
                let t = self.ellipse_t(phi);
                [a * t.sin(), b * (1.0 - t.cos())]
            }
            ArchType::LogSpiral => {
                let k = h.spiral_growth;
                let e = (k * phi).exp();
                let (s, c) = phi.sin_cos();
                let d = 1.0 + k * k;
                [
                    r * (e * (k * c + s) - k) / d,
                    r * (e * (k * s - c) + 1.0) / d,
                ]
            }
        }
    }

    /// Arc length from the crown to tangent angle `phi`.
    pub fn arc_length(&self, phi: f64) -> f64 {
        let h = &self.arch;
        let r = h.radius_m;
        match self.kind {
            ArchType::Circular => r * phi,
            ArchType::ThreeCentred => {
                let p0 = h.central_half_angle;
                if phi <= p0 {
                    r * phi
                } else {
                    r * p0 + h.outer_radius_m * (phi - p0)
                }
            }
            ArchType::Parabolic => {
                let (t, sec) = (phi.tan(), 1.0 / phi.cos());
                0.5 * r * (t * sec + (sec + t).ln())
            }
            ArchType::Elliptical => {
                let (a, b) = self.semi_axes();
                let t = self.ellipse_t(phi);
                simpson(
                    |u| (a * a * u.cos().powi(2) + b * b * u.sin().powi(2)).sqrt(),
                    t,
                )
            }
            ArchType::LogSpiral => {
                let k = h.spiral_growth;
                if k == 0.0 {
                    r * phi
                } else {
                    r * (k * phi).exp_m1() / k
                }
            }
        }
    }

    /// The tangent angle at arc length `s` from the crown; `None` when the
    /// half-curve is shorter than `s` up to [`MAX_ANGLE`].
    pub fn angle_at_length(&self, s: f64) -> Option<f64> {
        if s.is_nan() || s < 0.0 || self.arc_length(MAX_ANGLE) < s {
            return None;
        }
        if let ArchType::Circular = self.kind {
            return Some(s / self.arch.radius_m);
        }
        let (mut lo, mut hi) = (0.0, MAX_ANGLE);
        // s(φ) is strictly increasing: bisect to the last bit.
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.arc_length(mid) < s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    fn semi_axes(&self) -> (f64, f64) {
        let (r, q) = (self.arch.radius_m, self.arch.axis_ratio);
        (r / q, r / (q * q))
    }

    /// Ellipse parameter t of tangent angle φ: tan t = q tan φ.
    fn ellipse_t(&self, phi: f64) -> f64 {
        (self.arch.axis_ratio * phi.tan()).atan()
    }
}

fn circle(r: f64, phi: f64) -> [f64; 2] {
    let (s, c) = phi.sin_cos();
    [r * s, r * (1.0 - c)]
}

/// ∫₀ᵗ f by composite Simpson over 512 panels.
fn simpson(f: impl Fn(f64) -> f64, t: f64) -> f64 {
    const N: usize = 512;
    let h = t / N as f64;
    let mut sum = f(0.0) + f(t);
    for i in 1..N {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(i as f64 * h);
    }
    sum * h / 3.0
}
