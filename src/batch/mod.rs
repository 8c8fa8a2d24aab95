//! Batch solving over many datasets.
