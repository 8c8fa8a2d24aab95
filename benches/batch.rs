//! Batch solving over many datasets (issue 6).
fn main() {}
