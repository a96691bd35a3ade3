//! The soak's random numbers: the machine's SplitMix64 (`machine::rng`), which the simulated
//! PLC draws its delays from too, so one generator and one sequence serve both.

pub use crate::machine::rng::SplitMix64;
