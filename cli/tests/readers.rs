//! Every file reader fed random bytes and damaged files (proptest, fixed seed): scene TOML and the
//! CSV tables it names, comparison files, `--points` CSVs, PNG and TIFF frames and target images
//! (random bytes, random IHDR sizes up to 2³² − 1 a side), series files and the stacks they name,
//! and shard CSVs. None panics; each refusal is a message that names the file; a header's sizes
//! are checked before anything is allocated for them.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// A scratch directory unique to this process and `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-readers-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A runner with a fixed seed and `cases` cases.
fn runner(cases: u32) -> TestRunner {
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]))
}

/// Bytes: random, or `valid` damaged (bytes overwritten, then cut at a random length).
fn damaged(valid: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let n = valid.len().max(1);
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..600),
        (prop::collection::vec((0..n, any::<u8>()), 0..8), 0..=n).prop_map(move |(edits, cut)| {
            let mut bytes = valid.clone();
            for (i, b) in edits {
                if i < bytes.len() {
                    bytes[i] = b;
                }
            }
            bytes.truncate(cut);
            bytes
        }),
    ]
}

/// Checks a reader's verdict on `path`: Ok, or an error whose message names the file `named`.
fn named<T>(result: Result<T, String>, named: &Path) -> Result<(), TestCaseError> {
    if let Err(message) = result {
        let name = named.file_name().unwrap().to_string_lossy().into_owned();
        prop_assert!(message.contains(&name), "the message does not name {name}: {message}");
    }
    Ok(())
}

/// CRC-32 (ISO-HDLC) of PNG chunks, bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// A PNG whose IHDR claims `width × height` 16-bit grey pixels, with one empty IDAT: 69 bytes.
fn png_header_only(width: u32, height: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend((data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend(data);
        out.extend(&body);
        out.extend(crc32(&body).to_be_bytes());
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([16, 0, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
    chunk(b"IEND", &[]);
    out
}

/// A valid 16-bit grey PNG of 6 × 4 pixels.
fn valid_png() -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 6, 4);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    encoder.write_header().unwrap().write_image_data(&[7; 48]).unwrap();
    bytes
}

/// A valid 16-bit grey TIFF of 6 × 4 pixels.
fn valid_tiff() -> Vec<u8> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    tiff::encoder::TiffEncoder::new(&mut bytes)
        .unwrap()
        .write_image::<tiff::encoder::colortype::Gray16>(6, 4, &[300; 24])
        .unwrap();
    bytes.into_inner()
}

#[test]
fn png_and_tiff_frames_and_targets() {
    let dir = scratch("frames");
    let (png_path, tif_path) = (dir.join("frame.png"), dir.join("frame.tif"));
    runner(200)
        .run(&(damaged(valid_png()), damaged(valid_tiff())), |(png_bytes, tif_bytes)| {
            std::fs::write(&png_path, &png_bytes).unwrap();
            std::fs::write(&tif_path, &tif_bytes).unwrap();
            named(imaging::read_frame(&png_path).map_err(|e| e.to_string()), &png_path)?;
            named(imaging::read_frame(&tif_path).map_err(|e| e.to_string()), &tif_path)?;
            named(imaging::target::from_png(&png_path, 3).map_err(|e| e.to_string()), &png_path)?;
            Ok(())
        })
        .unwrap();
}

/// Random sizes in the IHDR, small or up to 2³² − 1 a side: the header is read, the size
/// refused before the image buffer is allocated (100 000² 16-bit pixels would be 20 GB).
#[test]
fn png_headers_of_any_size_are_checked_before_decoding() {
    let dir = scratch("headers");
    let path = dir.join("claims.png");
    let side = prop_oneof![1u32..64, 5000u32..20_000, 20_000u32..=u32::MAX];
    runner(120)
        .run(&(side.clone(), side), |(w, h)| {
            let bytes = png_header_only(w, h);
            std::fs::write(&path, &bytes).unwrap();
            let frame = imaging::read_frame(&path).map_err(|e| e.to_string());
            if u64::from(w) * u64::from(h) > imaging::frames::MAX_FRAME_PIXELS {
                let message = frame.as_ref().err().cloned().unwrap_or_default();
                prop_assert!(
                    message.contains("more than the 67108864 pixels a frame may have"),
                    "{w} × {h}: {message}"
                );
            }
            named(frame, &path)?;
            named(imaging::target::from_png(&path, 3).map_err(|e| e.to_string()), &path)?;
            Ok(())
        })
        .unwrap();
    // a file of under 70 bytes claiming 100 000 × 100 000 pixels
    std::fs::write(&path, png_header_only(100_000, 100_000)).unwrap();
    assert!(std::fs::metadata(&path).unwrap().len() < 70);
    let e = imaging::read_frame(&path).unwrap_err().to_string();
    assert!(e.contains("claims.png: 100000 × 100000 pixels (10000000000 in all)"), "{e}");
    let e = imaging::target::from_png(&path, 3).unwrap_err().to_string();
    assert!(e.contains("claims.png: 100000 × 100000 pixels need a 300000 × 300000 fine grid"), "{e}");
}

const SCENE: &str = include_str!("../../examples/paper-theory.toml");

#[test]
fn scene_files_and_their_tables() {
    let dir = scratch("scenes");
    let scene = dir.join("scene.toml");
    let with_table = dir.join("tabled.toml");
    let table = dir.join("qe.csv");
    std::fs::write(&with_table, SCENE.replace("quantum_efficiency = 0.2 ", "quantum_efficiency = \"qe.csv\" "))
        .unwrap();
    let qe = b"wavelength_nm,qe\n700,0.2\n800,0.3\n900,0.2\n".to_vec();
    runner(150)
        .run(&(damaged(SCENE.as_bytes().to_vec()), damaged(qe)), |(scene_bytes, table_bytes)| {
            std::fs::write(&scene, &scene_bytes).unwrap();
            named(scene::load(Some(&scene), &[]).map(|_| ()).map_err(|e| e.to_string()), &scene)?;
            std::fs::write(&table, &table_bytes).unwrap();
            named(scene::load(Some(&with_table), &[]).map(|_| ()).map_err(|e| e.to_string()), &table)?;
            Ok(())
        })
        .unwrap();
}

const DESIGNS: &str = include_str!("../../examples/designs.toml");

#[test]
fn comparison_and_points_files() {
    let dir = scratch("comparisons");
    let (designs, points) = (dir.join("designs.toml"), dir.join("points.csv"));
    let valid_points = b"lens.f_number,spectrum.range_nm\n2.5,50\n4,100\n".to_vec();
    runner(100)
        .run(&(damaged(DESIGNS.as_bytes().to_vec()), damaged(valid_points)), |(d, p)| {
            std::fs::write(&designs, &d).unwrap();
            named(scene::load_comparison(Some(&designs), &[]).map(|_| ()).map_err(|e| e.to_string()), &designs)?;
            std::fs::write(&points, &p).unwrap();
            named(scene::sweep::read_points(&points).map(|_| ()).map_err(|e| e.to_string()), &points)?;
            Ok(())
        })
        .unwrap();
}

#[test]
fn series_files_their_stacks_and_shard_csvs() {
    let dir = scratch("series");
    let (series, shard) = (dir.join("series.toml"), dir.join("shard.csv"));
    for stack in ["dark", "a", "b", "c"] {
        std::fs::create_dir_all(dir.join(stack)).unwrap();
    }
    let valid_series = b"region = \"0,0,6,4\"\n[dark]\nframes = [\"dark\"]\n[[levels]]\nillumination = 1.0\nframes = [\"a\"]\n[[levels]]\nillumination = 2.0\nframes = [\"b/*.png\"]\n[[levels]]\nillumination = 4.0\nframes = [\"c\"]\n".to_vec();
    let valid_shard = b"index,lens.f_number,asnr\n1,2.5,10.5\n0,2,\"11.5\"\n".to_vec();
    runner(100)
        .run(
            &(damaged(valid_series), damaged(valid_shard), damaged(valid_png()), damaged(valid_png())),
            |(s, c, f0, f1)| {
                for stack in ["dark", "a", "b", "c"] {
                    std::fs::write(dir.join(stack).join("f0.png"), &f0).unwrap();
                    std::fs::write(dir.join(stack).join("f1.png"), &f1).unwrap();
                }
                std::fs::write(&series, &s).unwrap();
                // the command as the binary runs it (its library's one entry point), the error
                // chain as it prints it
                let command = |args: &[&std::ffi::OsStr]| {
                    let cli = <asnr::Cli as clap::Parser>::try_parse_from(args).map_err(|e| e.to_string())?;
                    asnr::run(cli).map_err(|e| format!("{e:#}"))
                };
                named(
                    command(&["asnr".as_ref(), "characterize".as_ref(), series.as_os_str(), "--json".as_ref()]),
                    &series,
                )?;
                std::fs::write(&shard, &c).unwrap();
                named(command(&["asnr".as_ref(), "merge".as_ref(), shard.as_os_str()]), &shard)?;
                Ok(())
            },
        )
        .unwrap();
}
