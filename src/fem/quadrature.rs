//! Gauss–Legendre quadrature on [−1, 1] and its tensor products on the
//! reference square [−1, 1]² (quad4 faces) and cube [−1, 1]³ (hex8).
//!
//! An n-point rule integrates polynomials of degree ≤ 2n − 1 exactly in each
//! variable. Points and weights are computed by Newton iteration on the
//! Legendre polynomial P_n (to machine precision) and checked in the tests
//! against the closed forms for n = 1..5.
//!
//! The hot element kernels use the precomputed 2-point constants
//! ([`GAUSS2`], [`GAUSS2_HEX`], [`GAUSS2_QUAD`]) to avoid allocating per element.

/// 1/√3, the abscissa of the 2-point Gauss–Legendre rule (weights 1).
pub const GAUSS2: f64 = 0.577_350_269_189_625_8;

/// 2×2×2 Gauss points on the reference cube in VTK corner order (all weights 1).
pub const GAUSS2_HEX: [[f64; 3]; 8] = [
    [-GAUSS2, -GAUSS2, -GAUSS2],
    [GAUSS2, -GAUSS2, -GAUSS2],
    [GAUSS2, GAUSS2, -GAUSS2],
    [-GAUSS2, GAUSS2, -GAUSS2],
    [-GAUSS2, -GAUSS2, GAUSS2],
    [GAUSS2, -GAUSS2, GAUSS2],
    [GAUSS2, GAUSS2, GAUSS2],
    [-GAUSS2, GAUSS2, GAUSS2],
];

/// 2×2 Gauss points on the reference square in quad4 corner order (all weights 1).
pub const GAUSS2_QUAD: [[f64; 2]; 4] = [
    [-GAUSS2, -GAUSS2],
    [GAUSS2, -GAUSS2],
    [GAUSS2, GAUSS2],
    [-GAUSS2, GAUSS2],
];

/// Largest number of points per direction accepted by [`gauss_legendre`].
pub const MAX_POINTS: usize = 64;

/// A quadrature rule on the D-dimensional reference cell [−1, 1]^D:
/// ∫ f ≈ Σ_q `weights[q]` · f(`points[q]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Rule<const D: usize> {
    pub points: Vec<[f64; D]>,
    pub weights: Vec<f64>,
}

impl<const D: usize> Rule<D> {
    /// Number of quadrature points.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True for a rule without points (never produced by the constructors here).
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Iterate over (point, weight) pairs.
    pub fn iter(&self) -> impl Iterator<Item = ([f64; D], f64)> + '_ {
        self.points
            .iter()
            .copied()
            .zip(self.weights.iter().copied())
    }

    /// Σ_q w_q f(x_q).
    pub fn integrate(&self, mut f: impl FnMut([f64; D]) -> f64) -> f64 {
        self.iter().map(|(x, w)| w * f(x)).sum()
    }
}

/// Legendre polynomial P_n(x) and its derivative, by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    // P_n'(x) = n (x P_n − P_{n−1}) / (x² − 1); Gauss nodes are interior.
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

/// The n-point Gauss–Legendre rule on [−1, 1], points in increasing order.
///
/// # Panics
/// If `n == 0` or `n > MAX_POINTS`.
pub fn gauss_legendre(n: usize) -> Rule<1> {
    assert!(
        (1..=MAX_POINTS).contains(&n),
        "Gauss–Legendre rule needs 1..={MAX_POINTS} points, got {n}"
    );
    let mut points = vec![[0.0]; n];
    let mut weights = vec![0.0; n];
    let m = n.div_ceil(2);
    for i in 0..m {
        // Tricomi's initial guess for the i-th largest root.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            let dx = p / dp;
            x -= dx;
            if dx.abs() <= 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, x);
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // symmetric pair: −x at index i, +x at index n−1−i
        points[i] = [-x];
        points[n - 1 - i] = [x];
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    if n % 2 == 1 {
        points[n / 2] = [0.0];
    }
    Rule { points, weights }
}

/// n×n tensor Gauss rule on [−1, 1]²; the first coordinate varies fastest.
pub fn gauss_quad(n: usize) -> Rule<2> {
    let g = gauss_legendre(n);
    let mut points = Vec::with_capacity(n * n);
    let mut weights = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            points.push([g.points[i][0], g.points[j][0]]);
            weights.push(g.weights[i] * g.weights[j]);
        }
    }
    Rule { points, weights }
}

/// n×n×n tensor Gauss rule on [−1, 1]³; the first coordinate varies fastest.
pub fn gauss_hex(n: usize) -> Rule<3> {
    let g = gauss_legendre(n);
    let mut points = Vec::with_capacity(n * n * n);
    let mut weights = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                points.push([g.points[i][0], g.points[j][0], g.points[k][0]]);
                weights.push(g.weights[i] * g.weights[j] * g.weights[k]);
            }
        }
    }
    Rule { points, weights }
}
