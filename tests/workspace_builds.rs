#[test] fn builds() { fem_core::x(); }
