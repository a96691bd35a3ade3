//! The NC language: one NC line → `Block`, expressions and their evaluation.
