//! Transverse joints: contact before grouting, thin bonded layer after.
