//! Names syn, the build-dependency whose features this package exists for (Cargo.toml says why).

use syn as _;

fn main() {}
