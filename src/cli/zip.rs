//! A zip archive of stored (uncompressed) files: what an FMU needs. The
//! format is small (a local header before each file, a central directory,
//! its end record; PKWARE's APPNOTE 4.3), so lagc writes it by hand rather
//! than take a compression library for files importers read once.

/// CRC-32 (IEEE, reflected), as zip wants it.
fn crc32(bytes: &[u8]) -> u32 {
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

/// The archive of `files` (`(name, contents)`, names with `/`), stored.
/// Sizes must fit zip's 32 bits (an FMU's library does).
pub fn stored(files: &[(&str, &[u8])]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    let u16le = |v: usize| -> Result<[u8; 2], String> {
        u16::try_from(v)
            .map(u16::to_le_bytes)
            .map_err(|_| "too many files or too long a name for a zip archive".to_string())
    };
    let u32le = |v: usize| -> Result<[u8; 4], String> {
        u32::try_from(v)
            .map(u32::to_le_bytes)
            .map_err(|_| "a file too large for a zip archive".to_string())
    };
    for (name, contents) in files {
        let offset = out.len();
        let crc = crc32(contents).to_le_bytes();
        let size = u32le(contents.len())?;
        let name_len = u16le(name.len())?;
        // Version 2.0, no flags, method 0 (stored), time and date 0 (1980).
        let common = |v: &mut Vec<u8>| {
            v.extend_from_slice(&20u16.to_le_bytes());
            v.extend_from_slice(&0u16.to_le_bytes());
            v.extend_from_slice(&0u16.to_le_bytes());
            v.extend_from_slice(&0u16.to_le_bytes());
            v.extend_from_slice(&0x21u16.to_le_bytes());
            v.extend_from_slice(&crc);
            v.extend_from_slice(&size);
            v.extend_from_slice(&size);
            v.extend_from_slice(&name_len);
            v.extend_from_slice(&0u16.to_le_bytes());
        };
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        common(&mut out);
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(contents);
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        // Made by version 2.0 (MS-DOS attributes).
        central.extend_from_slice(&20u16.to_le_bytes());
        common(&mut central);
        // Comment length, disk, internal and external attributes.
        central.extend_from_slice(&0u16.to_le_bytes());
        central.extend_from_slice(&0u16.to_le_bytes());
        central.extend_from_slice(&0u16.to_le_bytes());
        central.extend_from_slice(&0u32.to_le_bytes());
        central.extend_from_slice(&u32le(offset)?);
        central.extend_from_slice(name.as_bytes());
    }
    let directory = out.len();
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&u16le(files.len())?);
    out.extend_from_slice(&u16le(files.len())?);
    out.extend_from_slice(&u32le(central.len())?);
    out.extend_from_slice(&u32le(directory)?);
    out.extend_from_slice(&0u16.to_le_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{crc32, stored};

    #[test]
    fn crc32_has_its_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn an_archive_lists_its_files_where_they_are() {
        let zip = stored(&[("a.txt", b"hello"), ("b/c.bin", &[0, 1, 2])]).unwrap();
        // The end record points at the central directory, whose entries
        // point at the local headers.
        let end = zip.len() - 22;
        assert_eq!(&zip[end..end + 4], &0x0605_4b50u32.to_le_bytes());
        let directory = u32::from_le_bytes(zip[end + 16..end + 20].try_into().unwrap()) as usize;
        assert_eq!(
            &zip[directory..directory + 4],
            &0x0201_4b50u32.to_le_bytes()
        );
        assert_eq!(&zip[30..35], b"a.txt");
        assert_eq!(&zip[35..40], b"hello");
    }
}
