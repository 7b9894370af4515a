//! The `.npy` writer (format 1.0, little-endian, C order) of the project's own files: `asnr psf
//! --stack`, and the maps, layouts and images the tests and the benchmarks write. The reader is
//! the PSF stack reader in `psf.rs` (it takes more: format 2.0, big-endian, Fortran order).
//!
//! The format (numpy's `format.py`, "NPY format version 1.0"): the magic `\x93NUMPY`, the
//! version bytes `1, 0`, the header's length as a little-endian u16, the header — the Python
//! literal `{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }` padded with spaces and
//! ended by a newline so that magic, version, length and header together fill a multiple of 64
//! bytes — then the data.

/// The element types written: `<f4` (f32) and `<f8` (f64), little-endian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NpyType {
    /// `<f4`
    F32,
    /// `<f8`
    F64,
}

impl NpyType {
    /// numpy's `descr` of the type.
    pub fn descr(self) -> &'static str {
        match self {
            NpyType::F32 => "<f4",
            NpyType::F64 => "<f8",
        }
    }
}

/// The bytes before the data of a `.npy` 1.0 file of `shape` (C order) and element type
/// `kind`: magic, version, length and header (module docs). A 1-D shape is written `(n,)`, as
/// Python writes a one-element tuple.
pub fn npy_header(kind: NpyType, shape: &[usize]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let dims = if dims.len() == 1 { format!("{},", dims[0]) } else { dims.join(", ") };
    let mut header = format!("{{'descr': '{}', 'fortran_order': False, 'shape': ({dims}), }}", kind.descr());
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    // a shape of a few dimensions gives a header of well under 64 KiB
    bytes.extend_from_slice(&u16::try_from(header.len()).unwrap_or(u16::MAX).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes
}

/// A whole `.npy` 1.0 file of a float32 phase map, `[y, x]` in C order, of `n × n` cells of
/// `pitch` (m), row `j` at `y = (j − (n − 1)/2) pitch`: the hyperbolic phase
/// `−(2π/λ0)(√(r² + f0²) − f0)` of focal length `f0` and design wavelength `lambda0` (m) plus
/// the cubic term `alpha ((x/R)³ + (y/R)³)` (radians, `R = radius`), wrapped to [0, 2π) — the
/// formula of `examples/phase-map-cubic.toml`'s map (`alpha` = 30 rad, R = 0.672 mm) and, with
/// `alpha` = 0, of `examples/phase-map-square.toml`'s, which `cargo xtask data --maps` writes by
/// the same formula (the task runner depends on no workspace crate).
pub fn hyperbolic_cubic_map(n: usize, pitch: f64, f0: f64, lambda0: f64, radius: f64, alpha: f64) -> Vec<u8> {
    let k0 = std::f64::consts::TAU / lambda0;
    let mut bytes = npy_header(NpyType::F32, &[n, n]);
    bytes.reserve(4 * n * n);
    let centre = |k: usize| (k as f64 - 0.5 * (n as f64 - 1.0)) * pitch;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (centre(i), centre(j));
            let phase =
                -k0 * ((x * x + y * y + f0 * f0).sqrt() - f0) + alpha * ((x / radius).powi(3) + (y / radius).powi(3));
            bytes.extend_from_slice(&(phase.rem_euclid(std::f64::consts::TAU) as f32).to_le_bytes());
        }
    }
    bytes
}

/// A whole `.npy` 1.0 file of the f64 `values` of `shape` (C order: the last index fastest).
/// `None` where the shape's product is not the number of values.
pub fn npy_f64(shape: &[usize], values: &[f64]) -> Option<Vec<u8>> {
    (shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)) == Some(values.len())).then(|| {
        let mut bytes = npy_header(NpyType::F64, shape);
        bytes.reserve(8 * values.len());
        values.iter().for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
        bytes
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The writer's files read back by the project's reader (the PSF stack's: slices of at least
    /// 8 × 8), shape and values, for f64 and f32, 2-D and 3-D; the header fills a multiple of 64 bytes, as numpy's does; a 1-D shape is
    /// written as Python's one-element tuple.
    #[test]
    fn written_files_read_back() {
        for (shape, dims) in [(vec![9, 8], [1, 9, 8]), (vec![2, 8, 10], [2, 8, 10])] {
            let n: usize = shape.iter().product();
            let values: Vec<f64> = (0..n).map(|i| 0.25 * i as f64 - 1.5).collect();
            let bytes = npy_f64(&shape, &values).unwrap();
            assert_eq!(npy_header(NpyType::F64, &shape).len() % 64, 0);
            let mut f32_bytes = npy_header(NpyType::F32, &shape);
            values.iter().for_each(|&v| f32_bytes.extend_from_slice(&(v as f32).to_le_bytes()));
            for file in [bytes, f32_bytes] {
                let stack = crate::psf::parse_npy(&file).unwrap();
                assert_eq!([stack.depth, stack.ny, stack.nx], dims);
                assert_eq!(stack.values, values);
            }
        }
        let one = npy_header(NpyType::F64, &[5]);
        assert!(String::from_utf8_lossy(&one).contains("'shape': (5,), }"));
        assert!(npy_f64(&[2, 3], &[0.0; 5]).is_none());
    }

    /// The examples' phase map: a 3 × 3 map of 1 µm cells is the header and nine float32 values, the centre cell the axis (phase 0), the cell right of
    /// it at x = 1 µm the formula's sag term plus the cubic term, wrapped to [0, 2π), written
    /// out here.
    #[test]
    fn hyperbolic_cubic_map_holds_its_formula() {
        let (f0, lambda0, radius, alpha) = (3.36e-3, 800e-9, 0.672e-3, 30.0);
        let bytes = hyperbolic_cubic_map(3, 1e-6, f0, lambda0, radius, alpha);
        assert_eq!(bytes.len(), npy_header(NpyType::F32, &[3, 3]).len() + 9 * 4);
        assert!(
            String::from_utf8_lossy(&bytes[..bytes.len() - 36])
                .contains("'descr': '<f4', 'fortran_order': False, 'shape': (3, 3)")
        );
        let values: Vec<f64> = bytes[bytes.len() - 36..]
            .chunks_exact(4)
            .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect();
        assert_eq!(values[4], 0.0);
        let x: f64 = 1e-6;
        let sag = -(std::f64::consts::TAU / lambda0) * ((x * x + f0 * f0).sqrt() - f0);
        let expected = (sag + alpha * (x / radius).powi(3)).rem_euclid(std::f64::consts::TAU) as f32;
        assert_eq!(values[5], f64::from(expected));
        // the row below (y = +1 µm, x = 0) the same by the formula's symmetry in x and y
        assert_eq!(values[7], values[5]);
    }
}
