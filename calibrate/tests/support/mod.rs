//! Test support for the calibrate crate's integration tests: the independent
//! trial generator ([`generator`]) and the bundles and campaigns made from it
//! ([`bundles`]).

pub mod bundles;
pub mod generator;
