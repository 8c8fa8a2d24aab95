//! Detection throughput (placeholder while the detector is being written).
fn main() {}
