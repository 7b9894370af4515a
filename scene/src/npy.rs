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
}
