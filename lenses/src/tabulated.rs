//! A lens given by measured or simulated transfer functions, and the text formats they come in.
//!
//! This is what the paper did with its Zemax and measured MTFs: the lens is one imaging order
//! whose OTF is a table against wavelength and frequency ([`optics::OtfTable`],
//! [`Pupil::Table`]), with efficiency and transmission tables beside it. Two text formats are
//! read, from text handed over by the caller (this crate reads no files):
//!
//! - [`parse_zemax_fft_mtf`]: the text listing of an FFT MTF analysis as Zemax (OpticStudio)
//!   writes it (UTF-16 with a byte-order mark, UTF-8, or Latin-1), one wavelength or a range per
//!   listing, one block per field; [`zemax_otf_table`] stacks monochromatic listings into a table.
//! - [`mtf_table_from_rows`]: a long-format CSV, `wavelength_nm, frequency_cyc_per_mm, mtf[, sagittal]`,
//!   from its rows (read by `scene` with the project's CSV reader).

use std::sync::Arc;

use optics::{Field, LensModel, Order, OtfTable, Pupil, Wavefront};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};

/// A lens whose single imaging order has a tabulated OTF (module docs; docs/physics.md, "Lens
/// families" and "Polychromatic OTF").
///
/// - `efficiency` τ(λ) and `transmission` T(λ) are fractions of the light incident on the full
///   clear aperture (`τ ≤ T ≤ 1`), measured or simulated with the table: nothing is
///   extrapolated.
/// - The table holds the OTF at the detector: each wavelength's row is what that wavelength
///   contributes, with its own defocus and aberrations already inside (the wavefront sign of
///   docs/physics.md, "Sign of the wavefront", is the table's business). The polychromatic OTF
///   is the signed sum of the rows with the photoelectron weights; a table of moduli (an MTF)
///   drops the sign of the rows where the OTF is negative, which the metric then cannot see.
/// - Nothing is extrapolated in wavelength: the end rows hold beyond the table, and the scene
///   refuses a detected spectrum with more than 0.1 % of its signal there. The Fraunhofer check
///   (paper SI eq. S15) takes the blur each row's OTF implies
///   ([`optics::fraunhofer::table_blur_radius`]) and counts the light outside the table as
///   beyond it.
/// - A measured MTF often already contains the camera's pixel MTF; the metric multiplies by the
///   pixel MTF itself when asked to, so such a table must not carry it twice:
///   [`new`](Self::new) divides it out (`includes_pixel_mtf`).
#[derive(Clone, Debug)]
pub struct Tabulated {
    f_number: f64,
    focal_length: f64,
    table: Arc<OtfTable>,
    efficiency: Curve,
    transmission: Curve,
    design_wavelength: Option<f64>,
    /// (pitch, frequency limit) of the pixel MTF divided out
    pixel_division: Option<(f64, f64)>,
}

/// The highest frequency up to which [`Tabulated::new`] divides a table by the pixel MTF
/// `sinc(ν p)` of pitch `p`, as a multiple of `1/p`: one half, the Nyquist frequency of that
/// pixel. The sinc falls to zero at `1/p`, so dividing near it amplifies the table's noise
/// without bound (×π/2 at Nyquist, ×6.4 at `0.95/p`, infinite at `1/p`), while the metric needs
/// the MTF only up to the camera's Nyquist frequency `1/(2p)`: the table is divided up to there
/// and cut (zero) beyond, which [`Tabulated::pixel_mtf_division`] reports.
pub const PIXEL_DIVISION_LIMIT: f64 = 0.5;

impl Tabulated {
    /// A tabulated lens of working F-number `f_number` (≥ 0.5) and focal length
    /// `focal_length_m` (> 0), whose order's OTF is `table`, with `efficiency` and
    /// `transmission` fractions (`τ ≤ T` at every wavelength).
    ///
    /// `includes_pixel_mtf`: `Some(pitch_m)` when the table already contains the pixel MTF
    /// `sinc(ν p)` of a square pixel of pitch `p` (a measured MTF, a camera-level simulation):
    /// every row is divided by it up to [`PIXEL_DIVISION_LIMIT`]` / p` (the pixel's Nyquist
    /// frequency, a sample inserted there by linear interpolation) and cut beyond; a divided
    /// value above 1 (a table that did not contain that pixel MTF) is refused.
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        table: OtfTable,
        efficiency: Curve,
        transmission: Curve,
        includes_pixel_mtf: Option<f64>,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        let anywhere = table.wavelengths()[0];
        check_efficiency_below_transmission(&|l| efficiency.value(l), &[&efficiency], &transmission, anywhere)?;
        let (table, pixel_division) = match includes_pixel_mtf {
            None => (table, None),
            Some(p) => {
                check("includes_pixel_mtf", p, p > 0.0, "a finite pixel pitch > 0 m")?;
                let limit = PIXEL_DIVISION_LIMIT / p;
                (divide_pixel_mtf(&table, p, limit)?, Some((p, limit)))
            }
        };
        Ok(Tabulated {
            f_number,
            focal_length: focal_length_m,
            table: Arc::new(table),
            efficiency,
            transmission,
            design_wavelength: None,
            pixel_division,
        })
    }

    /// This lens with a design wavelength (finite, > 0 m): the reference of the Fraunhofer
    /// check (paper SI eq. S15). Without one the lens reports none.
    pub fn with_design_wavelength(self, wavelength_m: f64) -> Result<Self, Error> {
        check("design_wavelength", wavelength_m, wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        Ok(Tabulated { design_wavelength: Some(wavelength_m), ..self })
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "tabulated"
    }

    /// The OTF table, after the pixel MTF was divided out.
    pub fn table(&self) -> &OtfTable {
        &self.table
    }

    /// `Some((pitch_m, limit))` when a pixel MTF was divided out: the pitch and the frequency
    /// (cycles/m) beyond which the table was cut.
    pub fn pixel_mtf_division(&self) -> Option<(f64, f64)> {
        self.pixel_division
    }
}

/// `table` with every row divided by `sinc(ν p)` up to `limit`, a sample inserted at `limit`,
/// and nothing beyond.
fn divide_pixel_mtf(table: &OtfTable, pitch: f64, limit: f64) -> Result<OtfTable, Error> {
    let freqs = table.frequencies();
    let mut kept: Vec<f64> = freqs.iter().copied().filter(|&f| f <= limit).collect();
    if table.max_frequency() > limit && *kept.last().expect("the first frequency is 0") < limit {
        kept.push(limit);
    }
    let rows = |azimuth: f64| -> Result<Vec<Vec<f64>>, Error> {
        table
            .wavelengths()
            .iter()
            .map(|&l| {
                kept.iter()
                    .map(|&nu| {
                        let v = table.value(l, nu, azimuth) / optics::pixel_mtf(pitch, nu);
                        if v.abs() > 1.0 + 1e-9 {
                            return Err(Error::PixelMtfNotInTable {
                                wavelength_nm: optics::round_for_display(l * 1e9),
                                frequency_cyc_per_mm: optics::round_for_display(nu * 1e-3),
                                value: v,
                                pitch_um: optics::round_for_display(pitch * 1e6),
                            });
                        }
                        Ok(v.clamp(-1.0, 1.0))
                    })
                    .collect()
            })
            .collect()
    };
    let tangential = rows(0.0)?;
    let sagittal = if table.is_direction_dependent() { Some(rows(std::f64::consts::FRAC_PI_2)?) } else { None };
    OtfTable::new(table.wavelengths().to_vec(), kept, tangential, sagittal).map_err(Error::Table)
}

impl LensModel for Tabulated {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
        vec![Order::new(
            self.efficiency.value(wavelength_m),
            Pupil::Table(Arc::clone(&self.table)),
            Wavefront::default(),
        )]
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.efficiency.value(wavelength_m)
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        self.design_wavelength
    }

    /// The tables are data: λ0 (`lens.design_wavelength_nm`) names the wavelength they were
    /// designed at for the Fraunhofer report's reference and enters no order, efficiency or
    /// transmission, so every quantity's derivative with respect to it is 0 (docs/physics.md,
    /// "Gradients: the design wavelength").
    fn design_wavelength_inert(&self) -> bool {
        true
    }

    /// The curves' samples and the table's wavelengths (the OTF is linear in λ between them).
    /// An efficiency or transmission table factored out (`crate::chromatic::factor_one_curve`).
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        crate::chromatic::factor_one_curve(&self.efficiency, &self.transmission, 1.0, |efficiency, transmission| {
            std::sync::Arc::new(Tabulated { efficiency, transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        crate::chromatic::curve_breakpoints(
            &self.efficiency,
            &self.transmission,
            self.table.wavelengths().iter().copied(),
        )
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let w = self.table.wavelengths();
        let pixel = match self.pixel_division {
            Some((p, limit)) => {
                format!(", pixel MTF of {} µm divided out up to {} cycles/mm", r(p * 1e6), r(limit * 1e-3))
            }
            None => String::new(),
        };
        format!(
            "tabulated lens F/{} f0 = {} mm, OTF at {} wavelength{} from {} to {} nm{pixel}",
            r(self.f_number),
            r(self.focal_length * 1e3),
            w.len(),
            if w.len() == 1 { "" } else { "s" },
            r(w[0] * 1e9),
            r(w[w.len() - 1] * 1e9),
        )
    }
}

// ---- text formats ----

/// `bytes` as text: UTF-16 LE or BE after its byte-order mark (or, without one, when every
/// other byte of the start is zero, as a BOM-less UTF-16 export), UTF-8 (with or without BOM),
/// else Latin-1 (ISO 8859-1: every byte one character), the encodings Zemax writes its text
/// listings in.
pub fn decode_text(bytes: &[u8]) -> Result<String, Error> {
    let utf16 = |body: &[u8], little: bool| -> Result<String, Error> {
        if !body.len().is_multiple_of(2) {
            return Err(Error::Parse {
                line: 0,
                expected: "UTF-16 text of an even number of bytes".into(),
                found: format!("{} bytes", body.len()),
            });
        }
        let units = body
            .chunks_exact(2)
            .map(|c| if little { u16::from_le_bytes([c[0], c[1]]) } else { u16::from_be_bytes([c[0], c[1]]) });
        char::decode_utf16(units).collect::<Result<String, _>>().map_err(|e| Error::Parse {
            line: 0,
            expected: "valid UTF-16 text".into(),
            found: format!("the unpaired surrogate {:#06x}", e.unpaired_surrogate()),
        })
    };
    match bytes {
        [0xFF, 0xFE, rest @ ..] => utf16(rest, true),
        [0xFE, 0xFF, rest @ ..] => utf16(rest, false),
        [0xEF, 0xBB, 0xBF, rest @ ..] => Ok(String::from_utf8_lossy(rest).into_owned()),
        _ => {
            let start = &bytes[..bytes.len().min(64) & !1];
            if start.len() >= 4 && start.chunks_exact(2).all(|c| c[1] == 0 && c[0] != 0) {
                return utf16(bytes, true);
            }
            if start.len() >= 4 && start.chunks_exact(2).all(|c| c[0] == 0 && c[1] != 0) {
                return utf16(bytes, false);
            }
            match std::str::from_utf8(bytes) {
                Ok(s) => Ok(s.to_owned()),
                Err(_) => Ok(bytes.iter().map(|&b| char::from(b)).collect()),
            }
        }
    }
}

/// One field's curves of a Zemax FFT MTF listing.
#[derive(Clone, Debug, PartialEq)]
pub struct ZemaxField {
    /// The text after `Field:` (e.g. `0.0000 (deg)` or `0.00, 20.00 mm`).
    pub label: String,
    /// The numbers in the label (one or two field coordinates), empty if none.
    pub position: Vec<f64>,
    /// Spatial frequencies, cycles/m.
    pub frequencies: Vec<f64>,
    /// Tangential MTF (or real part of the OTF) at each frequency.
    pub tangential: Vec<f64>,
    /// Sagittal MTF at each frequency (the tangential values when the listing has one column).
    pub sagittal: Vec<f64>,
}

impl ZemaxField {
    /// Whether this is the on-axis field (every coordinate of its label 0).
    pub fn is_on_axis(&self) -> bool {
        !self.position.is_empty() && self.position.iter().all(|&x| x == 0.0)
    }
}

/// A parsed Zemax FFT MTF text listing ([`parse_zemax_fft_mtf`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ZemaxMtf {
    /// The first line (e.g. `Polychromatic Diffraction MTF` or `Listing of FFT MTF Data`).
    pub title: String,
    /// The wavelength of a monochromatic listing (one value), or the range of a polychromatic
    /// one (two values), m, from the header's `Data for … µm` line.
    pub wavelengths_m: Vec<f64>,
    /// The field blocks in their order, without the diffraction-limit curve.
    pub fields: Vec<ZemaxField>,
}

/// Which field of a listing to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldChoice {
    /// The field whose coordinates are all 0.
    OnAxis,
    /// The field block of this index (from 0, the diffraction-limit curve not counted).
    Index(usize),
}

impl ZemaxMtf {
    /// The chosen field's block.
    pub fn field(&self, choice: FieldChoice) -> Result<&ZemaxField, Error> {
        match choice {
            FieldChoice::OnAxis => self.fields.iter().find(|f| f.is_on_axis()).ok_or_else(|| Error::Parse {
                line: 0,
                expected: "an on-axis field block (`Field: 0…`)".into(),
                found: format!("fields {:?}", self.fields.iter().map(|f| f.label.as_str()).collect::<Vec<_>>()),
            }),
            FieldChoice::Index(i) => self.fields.get(i).ok_or(Error::OutOfRange {
                name: "field index",
                value: i as f64,
                expected: "the index of one of the listing's field blocks, from 0",
            }),
        }
    }
}

/// Numbers of a line, after commas are made separators; `None` if a token is not a number.
fn numbers(text: &str) -> Option<Vec<f64>> {
    text.split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect()
}

/// The numbers found among the words of `text` (words that are not numbers skipped).
fn numbers_among(text: &str) -> Vec<f64> {
    text.split(|c: char| c.is_whitespace() || c == ',' || c == '(' || c == ')')
        .filter_map(|t| t.trim_end_matches('.').parse::<f64>().ok())
        .filter(|v| v.is_finite())
        .collect()
}

/// Frequency unit in cycles/m of a phrase like `cycles per mm`, `cycles/mm`, `lp/mm`.
fn frequency_unit(lower: &str) -> Option<f64> {
    let after = ["cycles per ", "cycles/", "cycle per ", "lp/", "line pairs per "]
        .iter()
        .find_map(|k| lower.find(k).map(|i| &lower[i + k.len()..]))?;
    let unit: String = after.trim_start().chars().take_while(|c| c.is_alphabetic()).collect();
    match unit.as_str() {
        "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => Some(1e3),
        "m" | "meter" | "meters" | "metre" | "metres" => Some(1.0),
        "µm" | "μm" | "um" | "micron" | "microns" => Some(1e6),
        "mrad" | "milliradian" | "milliradians" => None,
        _ => None,
    }
}

/// Parses the text listing of a Zemax FFT MTF analysis, as bytes (UTF-16 with BOM, UTF-8 or
/// Latin-1: [`decode_text`]).
///
/// The layout read (that of the listing a Zemax FFT MTF window writes with Text → Save; other
/// tools that read it look for the same lines):
///
/// ```text
/// Listing of FFT MTF Data                  (or: Polychromatic Diffraction MTF)
///
/// File : C:\…\lens.zmx
/// Title: …
/// Date : …
///
/// Data for 0.8000 µm.                      (or: Data for 0.4500 to 0.6500 microns.)
/// Spatial Frequency units are cycles per mm.
///
/// Field: 0.0000 (deg)
///   Spatial frequency      Tangential        Sagittal
///        0.000000            1.000000        1.000000
///       10.000000            0.952314        0.952314
///  …
/// Field: 10.0000 (deg)
///  …
/// ```
///
/// The wavelength line (`Data for … µm|microns|nm`) and the frequency unit (a line with
/// `cycles per mm`, `cycles/mm` or `lp/mm`; cycles per µm and per m also read) are required.
/// A block whose label names the diffraction limit is skipped. A data line is a frequency and
/// one or two values (tangential, sagittal). Errors name the line (from 1) and what was expected
/// there.
pub fn parse_zemax_fft_mtf(bytes: &[u8]) -> Result<ZemaxMtf, Error> {
    let text = decode_text(bytes)?;
    let mut title = String::new();
    let mut wavelengths_m: Option<Vec<f64>> = None;
    let mut unit: Option<f64> = None;
    let mut fields: Vec<ZemaxField> = Vec::new();
    let mut in_field = false; // inside a kept field block
    let mut skipping = false; // inside a diffraction-limit block
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.trim().trim_start_matches('\u{feff}');
        if line.is_empty() {
            continue;
        }
        if title.is_empty() {
            title = line.to_owned();
            continue;
        }
        let lower = line.to_lowercase();
        if let Some(rest) = line.strip_prefix("Field").map(str::trim_start).and_then(|r| r.strip_prefix(':')) {
            let label = rest.trim().to_owned();
            if label.to_lowercase().contains("diffraction") {
                skipping = true;
                in_field = false;
                continue;
            }
            skipping = false;
            in_field = true;
            let position = numbers_among(&label);
            fields.push(ZemaxField {
                label,
                position,
                frequencies: Vec::new(),
                tangential: Vec::new(),
                sagittal: Vec::new(),
            });
            continue;
        }
        if lower.starts_with("data for") {
            let is_um =
                lower.contains("µm") || lower.contains("μm") || lower.contains("micron") || lower.contains(" um");
            let scale = if is_um {
                1e-6
            } else if lower.contains("nm") {
                1e-9
            } else {
                return Err(Error::Parse {
                    line: line_no,
                    expected: "the wavelength line `Data for <λ> µm.` (µm, microns or nm)".into(),
                    found: line.to_owned(),
                });
            };
            let values: Vec<f64> = numbers_among(&line[8..]).into_iter().map(|v| v * scale).collect();
            if values.is_empty() || values.len() > 2 || values.iter().any(|&v| v <= 0.0) {
                return Err(Error::Parse {
                    line: line_no,
                    expected: "one wavelength or a range `<λ1> to <λ2>` > 0".into(),
                    found: line.to_owned(),
                });
            }
            wavelengths_m = Some(values);
            continue;
        }
        if lower.contains("cycles") || lower.contains("lp/") || lower.contains("line pairs") {
            if let Some(u) = frequency_unit(&lower) {
                unit = Some(u);
                continue;
            }
            if lower.contains(" per ") || lower.contains('/') {
                return Err(Error::Parse {
                    line: line_no,
                    expected: "a spatial frequency unit of cycles per mm (or per µm, per m)".into(),
                    found: line.to_owned(),
                });
            }
        }
        match numbers(line) {
            Some(v) if !v.is_empty() => {
                if skipping {
                    continue;
                }
                if !in_field {
                    return Err(Error::Parse {
                        line: line_no,
                        expected: "a `Field:` line before the data".into(),
                        found: line.to_owned(),
                    });
                }
                if !(v.len() == 2 || v.len() == 3) {
                    return Err(Error::Parse {
                        line: line_no,
                        expected: "a spatial frequency and the tangential (and sagittal) value".into(),
                        found: line.to_owned(),
                    });
                }
                let Some(scale) = unit else {
                    return Err(Error::Parse {
                        line: line_no,
                        expected: "the spatial frequency unit (e.g. `Spatial Frequency units are cycles per mm.`) before the data".into(),
                        found: line.to_owned(),
                    });
                };
                let f = fields.last_mut().expect("in a field block");
                let nu = v[0] * scale;
                if f.frequencies.last().is_some_and(|&prev| nu <= prev) {
                    return Err(Error::Parse {
                        line: line_no,
                        expected: "frequencies increasing within a field block".into(),
                        found: line.to_owned(),
                    });
                }
                f.frequencies.push(nu);
                f.tangential.push(v[1]);
                f.sagittal.push(*v.get(2).unwrap_or(&v[1]));
            }
            // headers, file names, dates, column titles: not data
            _ => {
                if in_field
                    && line.chars().next().is_some_and(|c| c.is_ascii_digit())
                    && fields.last().is_some_and(|f| !f.frequencies.is_empty())
                {
                    return Err(Error::Parse {
                        line: line_no,
                        expected: "a data line of numbers (frequency, tangential, sagittal)".into(),
                        found: line.to_owned(),
                    });
                }
            }
        }
    }
    let Some(wavelengths_m) = wavelengths_m else {
        return Err(Error::Parse {
            line: 0,
            expected: "a wavelength line `Data for <λ> µm.` in the header".into(),
            found: "none".into(),
        });
    };
    if unit.is_none() {
        return Err(Error::Parse {
            line: 0,
            expected: "the spatial frequency unit (`cycles per mm`) in the header".into(),
            found: "none".into(),
        });
    }
    if fields.is_empty() || fields.iter().any(|f| f.frequencies.len() < 2) {
        return Err(Error::Parse {
            line: 0,
            expected: "at least one `Field:` block with two or more data lines".into(),
            found: format!("{} field block(s)", fields.len()),
        });
    }
    Ok(ZemaxMtf { title, wavelengths_m, fields })
}

/// An OTF table from monochromatic Zemax listings, one per wavelength (any order), using the
/// chosen field of each: they must share the frequencies. A polychromatic listing (a range) is
/// refused: its curve is already a spectral average, not one wavelength's.
pub fn zemax_otf_table(listings: &[ZemaxMtf], field: FieldChoice) -> Result<OtfTable, Error> {
    check("listings", listings.len() as f64, !listings.is_empty(), "at least one listing")?;
    let mut rows: Vec<(f64, &ZemaxField)> = Vec::with_capacity(listings.len());
    for (i, l) in listings.iter().enumerate() {
        if l.wavelengths_m.len() != 1 {
            return Err(Error::Parse {
                line: 0,
                expected: format!("listing {i}: a monochromatic listing (one wavelength per table row)"),
                found: format!(
                    "a polychromatic range {:?} nm",
                    l.wavelengths_m.iter().map(|w| w * 1e9).collect::<Vec<_>>()
                ),
            });
        }
        rows.push((l.wavelengths_m[0], l.field(field)?));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let frequencies = rows[0].1.frequencies.clone();
    for (w, f) in &rows {
        if f.frequencies != frequencies {
            return Err(Error::Parse {
                line: 0,
                expected: "the same spatial frequencies in every listing".into(),
                found: format!("other frequencies at {} nm", optics::round_for_display(w * 1e9)),
            });
        }
    }
    let wavelengths = rows.iter().map(|r| r.0).collect();
    let tangential = rows.iter().map(|r| r.1.tangential.clone()).collect();
    let sagittal = rows.iter().map(|r| r.1.sagittal.clone()).collect();
    OtfTable::new(wavelengths, frequencies, tangential, Some(sagittal)).map_err(Error::Table)
}

/// The table of a long-format CSV of transfer functions, from its rows as read (the CSV rules
/// are the reader's: `scene` reads it with the project's one CSV reader): one row per wavelength
/// and frequency, `wavelength_nm, frequency_cyc_per_mm, mtf[, sagittal]` (the MTF, or the signed
/// OTF; the optional fourth column the sagittal curve), each with the line it came from (from
/// 1). Rows may come in any order; every wavelength must have the same frequencies, the first 0.
/// Errors name the line.
pub fn mtf_table_from_rows(input: &[(usize, Vec<f64>)]) -> Result<OtfTable, Error> {
    let mut rows: Vec<(f64, f64, f64, Option<f64>, usize)> = Vec::with_capacity(input.len());
    for (line_no, v) in input {
        let line_no = *line_no;
        let shown = || v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ");
        if !(v.len() == 3 || v.len() == 4) || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::Parse {
                line: line_no,
                expected: "wavelength_nm, frequency_cyc_per_mm, mtf[, sagittal]: three or four numbers".into(),
                found: shown(),
            });
        }
        if v[0] <= 0.0 || v[1] < 0.0 {
            return Err(Error::Parse {
                line: line_no,
                expected: "a wavelength > 0 nm and a frequency ≥ 0 cycles/mm".into(),
                found: shown(),
            });
        }
        rows.push((v[0] / 1e9, v[1] * 1e3, v[2], v.get(3).copied(), line_no));
    }
    if rows.is_empty() {
        return Err(Error::Parse { line: 0, expected: "data rows".into(), found: "none".into() });
    }
    let with_sagittal = rows[0].3.is_some();
    if let Some(r) = rows.iter().find(|r| r.3.is_some() != with_sagittal) {
        return Err(Error::Parse {
            line: r.4,
            expected: format!("{} columns on every row", if with_sagittal { 4 } else { 3 }),
            found: format!("{} columns", if r.3.is_some() { 4 } else { 3 }),
        });
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut wavelengths: Vec<f64> = Vec::new();
    let mut tangential: Vec<Vec<f64>> = Vec::new();
    let mut sagittal: Vec<Vec<f64>> = Vec::new();
    let mut freqs_of: Vec<Vec<(f64, usize)>> = Vec::new();
    for &(l, nu, t, s, line) in &rows {
        if wavelengths.last() != Some(&l) {
            wavelengths.push(l);
            tangential.push(Vec::new());
            sagittal.push(Vec::new());
            freqs_of.push(Vec::new());
        }
        let k = wavelengths.len() - 1;
        if freqs_of[k].last().is_some_and(|&(f, _)| f == nu) {
            return Err(Error::Parse {
                line,
                expected: "one row per wavelength and frequency".into(),
                found: format!("a second row at {} nm, {} cycles/mm", l * 1e9, nu * 1e-3),
            });
        }
        freqs_of[k].push((nu, line));
        tangential[k].push(t);
        sagittal[k].push(s.unwrap_or(t));
    }
    let frequencies: Vec<f64> = freqs_of[0].iter().map(|f| f.0).collect();
    for (k, f) in freqs_of.iter().enumerate() {
        if f.iter().map(|x| x.0).ne(frequencies.iter().copied()) {
            return Err(Error::Parse {
                line: f.first().map_or(0, |x| x.1),
                expected: "the same frequencies at every wavelength".into(),
                found: format!("other frequencies at {} nm", optics::round_for_display(wavelengths[k] * 1e9)),
            });
        }
    }
    OtfTable::new(wavelengths, frequencies, tangential, with_sagittal.then_some(sagittal)).map_err(Error::Table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(rows: Vec<Vec<f64>>) -> OtfTable {
        let n = rows.len();
        let waves = (0..n).map(|i| 500e-9 + 100e-9 * i as f64).collect();
        OtfTable::new(waves, vec![0.0, 5e4, 1e5, 2e5, 3e5], rows, None).unwrap()
    }

    #[test]
    fn one_order_through_the_table() {
        let t = table(vec![vec![1.0, 0.8, 0.6, 0.3, 0.1]]);
        let lens = Tabulated::new(2.5, 3.36e-3, t, Curve::Constant(0.3), Curve::Constant(0.5), None).unwrap();
        let o = &lens.orders(550e-9, Field::ON_AXIS)[0];
        assert_eq!(o.efficiency, 0.3);
        assert!(matches!(&o.pupil, Pupil::Table(t) if Arc::ptr_eq(t, &lens.table)));
        assert_eq!(lens.transmission(600e-9), 0.5);
        assert_eq!(lens.design_wavelength(), None);
        assert_eq!(lens.clone().with_design_wavelength(5e-7).unwrap().design_wavelength(), Some(5e-7));
        assert_eq!(lens.kind(), "tabulated");
        assert_eq!(lens.describe(), "tabulated lens F/2.5 f0 = 3.36 mm, OTF at 1 wavelength from 500 to 500 nm");
    }

    /// A 4 µm pixel: Nyquist 125 cycles/mm. The divided table is the original over the sinc up
    /// to there, a sample inserted at 125 cycles/mm, zero beyond.
    #[test]
    fn divides_the_pixel_mtf_up_to_the_pixel_nyquist_frequency() {
        let p = 4e-6;
        let otf = |nu: f64| 1.0 - nu / 4e5;
        let freqs = [0.0, 5e4, 1e5, 2e5, 3e5];
        let row: Vec<f64> = freqs.iter().map(|&nu| otf(nu) * optics::pixel_mtf(p, nu)).collect();
        let t = OtfTable::new(vec![5e-7], freqs.to_vec(), vec![row], None).unwrap();
        let lens = Tabulated::new(2.5, 3.36e-3, t, Curve::Constant(0.3), Curve::Constant(0.5), Some(p)).unwrap();
        assert_eq!(lens.pixel_mtf_division(), Some((p, 1.25e5)));
        assert_eq!(lens.table().frequencies(), &[0.0, 5e4, 1e5, 1.25e5]);
        for nu in [0.0, 5e4, 1e5] {
            assert!((lens.table().value(5e-7, nu, 0.0) - otf(nu)).abs() < 1e-12, "{nu}");
        }
        // the inserted sample: the table's linear interpolation over the sinc there
        let between = 0.75 * otf(1e5) * optics::pixel_mtf(p, 1e5) + 0.25 * otf(2e5) * optics::pixel_mtf(p, 2e5);
        assert!((lens.table().value(5e-7, 1.25e5, 0.0) - between / optics::pixel_mtf(p, 1.25e5)).abs() < 1e-12);
        assert_eq!(lens.table().value(5e-7, 1.3e5, 0.0), 0.0);
        assert!(lens.describe().ends_with("pixel MTF of 4 µm divided out up to 125 cycles/mm"), "{}", lens.describe());
        // a table that did not contain this pixel MTF: divided values above 1 are refused
        let flat = OtfTable::new(vec![5e-7], freqs.to_vec(), vec![vec![1.0, 1.0, 1.0, 0.9, 0.8]], None).unwrap();
        let e = Tabulated::new(2.5, 3.36e-3, flat, Curve::Constant(0.3), Curve::Constant(0.5), Some(p)).unwrap_err();
        assert!(e.to_string().contains("at 500 nm, 50 cycles/mm") && e.to_string().contains("4 µm"), "{e}");
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let t = || table(vec![vec![1.0, 0.8, 0.6, 0.3, 0.1]]);
        let e = Tabulated::new(0.2, 3e-3, t(), Curve::Constant(0.3), Curve::Constant(0.5), None).unwrap_err();
        assert!(e.to_string().contains("f_number = 0.2"), "{e}");
        let e = Tabulated::new(2.0, 3e-3, t(), Curve::Constant(0.6), Curve::Constant(0.5), None).unwrap_err();
        assert!(e.to_string().contains("exceeds transmission T = 0.5"), "{e}");
        let e = Tabulated::new(2.0, 3e-3, t(), Curve::Constant(0.3), Curve::Constant(0.5), Some(-1e-6)).unwrap_err();
        assert!(e.to_string().contains("includes_pixel_mtf = -0.000001"), "{e}");
        let e = Tabulated::new(2.0, 3e-3, t(), Curve::Constant(0.3), Curve::Constant(0.5), None)
            .unwrap()
            .with_design_wavelength(0.0)
            .unwrap_err();
        assert!(e.to_string().contains("design_wavelength = 0"), "{e}");
    }

    const LISTING: &str = "Listing of FFT MTF Data\n\nFile : C:\\lens.zmx\nTitle: test\nDate : 1/2/2026\n\n\
        Data for 0.8000 µm.\nSpatial Frequency units are cycles per mm.\n\nField: 0.0000 (deg)\n\
        Spatial frequency      Tangential        Sagittal\n  0.000  1.0000  1.0000\n  100.0  0.5000  0.6000\n\
        200.0  0.1000  0.2000\n\nField: 5.0000 (deg)\nSpatial frequency      Tangential        Sagittal\n\
        0.000  1.0000  1.0000\n  100.0  0.4000  0.5000\n  200.0  0.0500  0.1000\n";

    #[test]
    fn reads_a_zemax_listing() {
        let m = parse_zemax_fft_mtf(LISTING.as_bytes()).unwrap();
        assert_eq!(m.title, "Listing of FFT MTF Data");
        assert_eq!(m.wavelengths_m, vec![0.8e-6]);
        assert_eq!(m.fields.len(), 2);
        let f = m.field(FieldChoice::OnAxis).unwrap();
        assert_eq!(f.frequencies, vec![0.0, 1e5, 2e5]);
        assert_eq!(f.tangential, vec![1.0, 0.5, 0.1]);
        assert_eq!(f.sagittal, vec![1.0, 0.6, 0.2]);
        assert_eq!(m.field(FieldChoice::Index(1)).unwrap().position, vec![5.0]);
        assert!(m.field(FieldChoice::Index(2)).is_err());
        // Latin-1: µ is the byte 0xB5
        let latin1: Vec<u8> = LISTING.chars().map(|c| c as u32 as u8).collect();
        assert!(std::str::from_utf8(&latin1).is_err());
        assert_eq!(parse_zemax_fft_mtf(&latin1).unwrap(), m);
        // UTF-16 BE with BOM
        let be: Vec<u8> = [0xFE, 0xFF].into_iter().chain(LISTING.encode_utf16().flat_map(u16::to_be_bytes)).collect();
        assert_eq!(parse_zemax_fft_mtf(&be).unwrap(), m);
        // the table of one listing
        let t = zemax_otf_table(std::slice::from_ref(&m), FieldChoice::Index(1)).unwrap();
        assert_eq!(t.value(0.8e-6, 1e5, 0.0), 0.4);
        assert_eq!(t.value(0.8e-6, 1e5, std::f64::consts::FRAC_PI_2), 0.5);
    }

    #[test]
    fn zemax_errors_name_the_line() {
        let e = parse_zemax_fft_mtf(LISTING.replace("  100.0  0.5000  0.6000", "  100.0  0.5000  x").as_bytes())
            .unwrap_err();
        assert!(e.to_string().starts_with("line 13: expected a data line"), "{e}");
        let e = parse_zemax_fft_mtf(LISTING.replace("cycles per mm", "cycles per mrad").as_bytes()).unwrap_err();
        assert!(e.to_string().starts_with("line 8: expected a spatial frequency unit of cycles per mm"), "{e}");
        let e = parse_zemax_fft_mtf(LISTING.replace("Data for 0.8000 µm.", "").as_bytes()).unwrap_err();
        assert!(e.to_string().contains("expected a wavelength line"), "{e}");
        let e = parse_zemax_fft_mtf(LISTING.replace("200.0  0.1000  0.2000", "50.0  0.1000  0.2000").as_bytes())
            .unwrap_err();
        assert!(e.to_string().starts_with("line 14: expected frequencies increasing"), "{e}");
        let e = parse_zemax_fft_mtf(LISTING.replace("  100.0  0.5000  0.6000", "  100.0  0.5 0.6 0.7").as_bytes())
            .unwrap_err();
        assert!(e.to_string().starts_with("line 13: expected a spatial frequency and the tangential"), "{e}");
        let poly = parse_zemax_fft_mtf(LISTING.replace("0.8000 µm", "0.7000 to 0.9000 µm").as_bytes()).unwrap();
        assert_eq!(poly.wavelengths_m.len(), 2);
        let e = zemax_otf_table(&[poly], FieldChoice::OnAxis).unwrap_err();
        assert!(e.to_string().contains("monochromatic"), "{e}");
    }

    #[test]
    fn tables_a_long_csv() {
        // rows as the CSV reader hands them: numbers and their lines (from 1)
        let rows = |list: &[&[f64]]| -> Vec<(usize, Vec<f64>)> {
            list.iter().enumerate().map(|(i, r)| (i + 3, r.to_vec())).collect()
        };
        let t = mtf_table_from_rows(&rows(&[
            &[600.0, 0.0, 1.0],
            &[600.0, 100.0, 0.4],
            &[500.0, 0.0, 1.0],
            &[500.0, 100.0, 0.6],
        ]))
        .unwrap();
        assert_eq!(t.wavelengths(), &[500e-9, 600e-9]);
        assert_eq!(t.frequencies(), &[0.0, 1e5]);
        assert!((t.value(550e-9, 1e5, 0.0) - 0.5).abs() < 1e-15);
        let e = mtf_table_from_rows(&rows(&[&[500.0, 0.0, 1.0], &[500.0, 100.0]])).unwrap_err();
        assert!(e.to_string().starts_with("line 4: expected wavelength_nm, frequency_cyc_per_mm, mtf"), "{e}");
        let e = mtf_table_from_rows(&rows(&[&[-500.0, 0.0, 1.0]])).unwrap_err();
        assert!(e.to_string().contains("line 3") && e.to_string().contains("a wavelength > 0 nm"), "{e}");
        let e = mtf_table_from_rows(&rows(&[
            &[500.0, 0.0, 1.0],
            &[500.0, 100.0, 0.5],
            &[600.0, 0.0, 1.0],
            &[600.0, 90.0, 0.5],
        ]))
        .unwrap_err();
        assert!(e.to_string().contains("the same frequencies at every wavelength"), "{e}");
        let e = mtf_table_from_rows(&rows(&[&[500.0, 0.0, 1.0, 1.0], &[500.0, 100.0, 0.5]])).unwrap_err();
        assert!(e.to_string().contains("4 columns on every row"), "{e}");
        let sag = mtf_table_from_rows(&rows(&[&[500.0, 0.0, 1.0, 1.0], &[500.0, 100.0, 0.5, 0.3]])).unwrap();
        assert!(sag.is_direction_dependent());
    }
}
