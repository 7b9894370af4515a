//! FFT
