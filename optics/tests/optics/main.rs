//! Integration tests of the optics crate, one binary (STYLE.md): the fast OTF paths against
//! identities and references, the slow references themselves, and the FFT pupil engine.

mod fft;
mod line;
mod orders;
mod otf;
mod overlap;
mod properties;
mod radial;
mod reference;
mod site_map;
mod spectral;
mod tables;
mod zones;
