//! The `risotto` driver.
fn main() {}
