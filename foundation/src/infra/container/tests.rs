use super::*;

const FORMAT: Format = Format {
    magic: b"HPRTTEST",
    version: 3,
    what: "test file",
};

#[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Head {
    name: String,
    words: u64,
    bytes: u64,
}

fn head() -> Head {
    Head {
        name: "zwölf".into(),
        words: 3,
        bytes: 5,
    }
}

fn sample() -> Vec<u8> {
    encode(FORMAT, &head(), |w| {
        w.f32s(&[1.5, -0.0, f32::MAX])?;
        w.u32s(&[7, u32::MAX, 0])?;
        w.bytes(&[1, 2, 3, 4, 5])
    })
    .unwrap()
}

fn open(bytes: &[u8]) -> Result<Reader<std::io::Cursor<&[u8]>>, ContainerError> {
    Reader::new(
        Path::new("t.bin"),
        std::io::Cursor::new(bytes),
        bytes.len() as u64,
        FORMAT,
    )
}

/// `bytes` with its checksum made right again.
fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
    let n = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..n]);
    bytes[n..].copy_from_slice(&crc.to_le_bytes());
    bytes
}

#[test]
fn a_container_reads_back_what_was_written() {
    let bytes = sample();
    assert_eq!(bytes.len() % 4, 0);
    let mut reader = open(&bytes).unwrap();
    let h: Head = reader.header().unwrap();
    assert_eq!(h, head());
    let floats = reader.section::<f32>(h.words).unwrap();
    let words = reader.section::<u32>(h.words).unwrap();
    let small = reader.section::<u8>(h.bytes).unwrap();
    reader.check_filled().unwrap();
    let floats = reader.read_all(&floats).unwrap();
    assert_eq!(floats[0], 1.5);
    assert!(floats[1] == 0.0 && floats[1].is_sign_negative());
    assert_eq!(floats[2], f32::MAX);
    assert_eq!(reader.read(&words, 1..3).unwrap(), vec![u32::MAX, 0]);
    assert_eq!(reader.read_all(&small).unwrap(), vec![1, 2, 3, 4, 5]);
}

#[test]
fn a_file_written_atomically_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.bin");
    let output = AtomicOutput::create(&path).unwrap();
    let written = write_file(output, FORMAT, &head(), |w| w.u32s(&[1, 2, 3])).unwrap();
    assert_eq!(written, std::fs::metadata(&path).unwrap().len());
    let mut reader = Reader::open(&path, FORMAT, 1 << 20).unwrap();
    let section = reader.section::<u32>(3).unwrap();
    reader.check_filled().unwrap();
    assert_eq!(reader.read_all(&section).unwrap(), vec![1, 2, 3]);
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no partial left"
    );
    assert!(matches!(
        Reader::open(&path, FORMAT, written - 1),
        Err(ContainerError::Io { .. })
    ));
    assert!(matches!(
        Reader::open(Path::new("/dev/zero"), FORMAT, 1 << 20),
        Err(ContainerError::Io { .. })
    ));
}

#[test]
fn every_flipped_byte_is_caught() {
    let bytes = sample();
    for at in 16..bytes.len() {
        let mut flipped = bytes.clone();
        flipped[at] ^= 0x10;
        assert!(
            matches!(open(&flipped), Err(ContainerError::Checksum { .. })),
            "byte {at}"
        );
    }
}

#[test]
fn truncated_files_are_refused() {
    let bytes = sample();
    for len in [0, 10, 19] {
        assert!(matches!(
            open(&bytes[..len]),
            Err(ContainerError::Truncated { .. })
        ));
    }
    for len in [24, bytes.len() / 2, bytes.len() - 1] {
        let error = open(&bytes[..len]).err().expect("refused");
        assert!(
            matches!(
                error,
                ContainerError::Checksum { .. } | ContainerError::Truncated { .. }
            ),
            "{len}: {error}"
        );
    }
}

#[test]
fn another_format_or_version_is_refused_by_name() {
    let bytes = sample();
    let mut other = bytes.clone();
    other[..8].copy_from_slice(b"HPRTBAND");
    assert!(matches!(
        open(&resealed(other)),
        Err(ContainerError::BadMagic { .. })
    ));
    let mut older = bytes.clone();
    older[8..12].copy_from_slice(&2u32.to_le_bytes());
    let error = open(&resealed(older)).err().expect("refused");
    assert!(matches!(
        error,
        ContainerError::Version {
            found: 2,
            expected: 3,
            ..
        }
    ));
    assert!(
        error.to_string().contains("test file format version 2"),
        "{error}"
    );
}

#[test]
fn oversized_lengths_are_refused_without_allocating() {
    let bytes = sample();
    // A header longer than any hprt reads.
    let mut long = bytes.clone();
    long[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        open(&resealed(long)),
        Err(ContainerError::HeaderTooLarge { .. })
    ));
    // A header longer than the file.
    let mut past = bytes.clone();
    past[12..16].copy_from_slice(&(bytes.len() as u32).to_le_bytes());
    assert!(matches!(
        open(&resealed(past)),
        Err(ContainerError::Truncated { .. })
    ));
    // Sections larger than the file, or than any file: refused when claimed.
    let mut reader = open(&bytes).unwrap();
    assert!(matches!(
        reader.section::<f32>(1 << 40),
        Err(ContainerError::Length { .. })
    ));
    let error = reader.section::<u32>(u64::MAX).expect_err("refused");
    assert!(matches!(
        error,
        ContainerError::Length {
            described: DescribedSize::Overflow,
            ..
        }
    ));
    // Sections that leave bytes over.
    let mut reader = open(&bytes).unwrap();
    reader.section::<f32>(3).unwrap();
    let error = reader.check_filled().expect_err("refused");
    assert!(
        error
            .to_string()
            .contains("where its test file header describes"),
        "{error}"
    );
}

#[test]
fn an_unreadable_header_is_named() {
    let bytes = encode(FORMAT, &"not a head", |_| Ok(())).unwrap();
    let reader = open(&bytes).unwrap();
    let error = reader.header::<Head>().expect_err("refused");
    assert!(
        error.to_string().contains("unreadable test file header"),
        "{error}"
    );
}
