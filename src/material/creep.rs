//! Creep of concrete: Zhu Bofang's compliance and its exponential recursion.
