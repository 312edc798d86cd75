//! Placeholder: the MSH 4.1 reader and writer (being written).
