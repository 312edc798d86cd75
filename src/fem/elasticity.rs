//! Small-strain solid elasticity on hex8: B matrices, stiffness, loads, stresses.
