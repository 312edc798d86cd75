//! Placeholder: the Abaqus/CalculiX reader and writer (being written).
