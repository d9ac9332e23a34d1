use super::*;
use crate::SamplerKind;

fn spec() -> JobSpec {
    JobSpec {
        scene: PathBuf::from("/scenes/box.toml"),
        env: None,
        layout: None,
        rotate: Some(30.0),
        width: Some(5),
        height: Some(7),
        spp: 4,
        bounces: 2,
        seed: 1,
        sampler: SamplerKind::default(),
    }
}

/// Shard 1 of 3 of a 5×7 image: rows 1 and 4.
fn band() -> (BandHeader, ReferenceImage) {
    let (w, h) = (5, 2);
    let n = w * h;
    let image = ReferenceImage {
        radiance: RgbImageF32::new(w, h, (0..n).map(|i| Rgb::splat(i as f32)).collect()),
        specular: RgbImageF32::new(w, h, vec![Rgb::splat(0.25); n]),
        coverage: (0..n).map(|i| (i % 2) as f32).collect(),
        visibility: vec![0.5; n],
        primary: (0..n as u32).collect(),
        stats: RenderStats {
            rays: 1234,
            seconds: 0.1,
        },
    };
    let header = BandHeader {
        hprt: env!("CARGO_PKG_VERSION").to_owned(),
        job: spec(),
        fingerprint: "f".repeat(64),
        index: 1,
        count: 3,
        width: 5,
        height: 7,
        images: 1,
        files: vec![],
        stats: vec![BandStats {
            rays: 1234,
            seconds: 0.1,
        }],
    };
    (header, image)
}

fn message(bytes: &[u8]) -> String {
    match decode(Path::new("b.hprtband"), bytes) {
        Ok(_) => panic!("a damaged band was read"),
        Err(e) => e.to_string(),
    }
}

/// `bytes` with its JSON header edited by `edit`, padding and checksum made right.
fn edited(bytes: &[u8], edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let data = (16 + json_len).div_ceil(4) * 4;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + json_len]).unwrap();
    edit(&mut header);
    let json = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.resize(out.len().div_ceil(4) * 4, 0);
    out.extend_from_slice(&bytes[data..bytes.len() - 4]);
    let crc = crc32fast_hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// The CRC-32 (IEEE) the container uses, bit by bit (the test needs no crate for it).
fn crc32fast_hash(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn a_band_reads_back_what_was_rendered() {
    let (header, image) = band();
    let bytes = encode_band(&header, &[&image]);
    let read = decode(Path::new("b.hprtband"), &bytes).unwrap();
    assert_eq!(read.rows, vec![1, 4]);
    assert_eq!(read.header.job, spec());
    let back = &read.images[0];
    assert_eq!(back.radiance.pixels, image.radiance.pixels);
    assert_eq!(back.specular.pixels, image.specular.pixels);
    assert_eq!(back.coverage, image.coverage);
    assert_eq!(back.visibility, image.visibility);
    assert_eq!(back.primary, image.primary);
    assert_eq!(back.stats.rays, 1234);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(band_name(ShardSpec::new(1, 3).unwrap()));
    let output = AtomicOutput::create(&path).unwrap();
    assert_eq!(
        write_band(output, &header, &[&image]).unwrap(),
        bytes.len() as u64
    );
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    assert_eq!(read_band(&path).unwrap().rows, vec![1, 4]);
}

#[test]
fn damaged_or_impossible_bands_are_refused_with_the_reason() {
    let (header, image) = band();
    let bytes = encode_band(&header, &[&image]);
    // Re-sealed by the test's own CRC: still a band.
    assert!(decode(Path::new("b.hprtband"), &edited(&bytes, |_| ())).is_ok());
    assert!(message(&bytes[..bytes.len() - 8]).contains("checksum"));
    let mut shard = bytes.clone();
    shard[..8].copy_from_slice(b"HPRTSHRD");
    let n = shard.len() - 4;
    let crc = crc32fast_hash(&shard[..n]);
    shard[n..].copy_from_slice(&crc.to_le_bytes());
    assert!(message(&shard).contains("not an hprt reference band"));
    let text = message(&edited(&bytes, |h| h["hprt"] = "0.0.1".into()));
    assert!(text.contains("made by hprt 0.0.1"), "{text}");
    // Sizes no camera renders, or that overflow: refused before anything is allocated.
    for (w, h) in [(1u64 << 62, 4u64), (1 << 32, 1 << 32), (0, 7)] {
        let text = message(&edited(&bytes, |head| {
            head["width"] = w.into();
            head["height"] = h.into();
        }));
        assert!(text.contains("images of"), "{text}");
    }
    // A header that describes more pixels than the file holds.
    let text = message(&edited(&bytes, |h| h["width"] = 6.into()));
    assert!(
        text.contains("where its reference band header describes"),
        "{text}"
    );
    // Or fewer: the file's bytes must be the header's, exactly.
    let text = message(&edited(&bytes, |h| h["width"] = 4.into()));
    assert!(
        text.contains("where its reference band header describes"),
        "{text}"
    );
    let text = message(&edited(&bytes, |h| h["images"] = 2.into()));
    assert!(text.contains("2 images of 5x7"), "{text}");
    let text = message(&edited(&bytes, |h| h["index"] = 3.into()));
    assert!(text.contains("shard 3 of 3"), "{text}");
}
