//! No code: this package exists for its dependencies' features, which it names here so that
//! none of them is unused (workspace-hack/Cargo.toml says why it exists).

use approx as _;
use crc32fast as _;
use either as _;
use libc as _;
use matrixmultiply as _;
use memchr as _;
use nalgebra as _;
use num_rational as _;
use optics as _;
use rand as _;
use serde as _;
use serde_core as _;
use simba as _;
use simd_adler32 as _;
