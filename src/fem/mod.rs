//! Finite elements: quadrature, hex8, faces, kernels, sparse assembly, solvers.
