//! A zip archive of stored (uncompressed) entries written front to back, for answers that
//! are streamed (`trials.zip`): each entry's CRC-32 and length are known before its bytes
//! are written (the caller reads the entry twice), so no header is patched afterwards and
//! nothing but the central directory's few bytes per entry is held. Zip64 records are
//! written when an offset, a length or the entry count needs them (a hundred trials of
//! 64 MiB pass 4 GiB).

use std::io::{Read, Write};

/// A field of the classic format that says "see the zip64 record".
const MASKED: u32 = u32::MAX;

/// One entry written, for the central directory.
struct Entry {
    name: String,
    crc: u32,
    len: u64,
    offset: u64,
}

/// The archive being written to `out`.
pub(crate) struct StoredZip<W: Write> {
    out: W,
    written: u64,
    entries: Vec<Entry>,
    /// Lengths and offsets from this on are written as zip64 (`u32::MAX` in use; smaller
    /// in the tests, so that they reach the zip64 records with small entries).
    zip64_from: u64,
}

/// DOS time and date of every entry: 1980-01-01 00:00, the format's first day (the entries
/// are a session's files, whose time the archive does not carry).
const DOS_TIME: u16 = 0;
const DOS_DATE: u16 = (1 << 5) | 1;

impl<W: Write> StoredZip<W> {
    pub fn new(out: W) -> StoredZip<W> {
        StoredZip {
            out,
            written: 0,
            entries: Vec::new(),
            zip64_from: u64::from(MASKED),
        }
    }

    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.out.write_all(bytes)?;
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// Adds the entry `name` of `len` bytes with CRC-32 `crc` (see [`crc32`]), read from
    /// `bytes`; fewer or more bytes than `len` are an error.
    pub fn add(
        &mut self,
        name: &str,
        len: u64,
        crc: u32,
        bytes: &mut dyn Read,
    ) -> std::io::Result<()> {
        let offset = self.written;
        let large = len >= self.zip64_from;
        let mut head = Vec::with_capacity(30 + name.len() + 20);
        head.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        head.extend_from_slice(&version(large).to_le_bytes());
        head.extend_from_slice(&0u16.to_le_bytes()); // flags
        head.extend_from_slice(&0u16.to_le_bytes()); // stored
        head.extend_from_slice(&DOS_TIME.to_le_bytes());
        head.extend_from_slice(&DOS_DATE.to_le_bytes());
        head.extend_from_slice(&crc.to_le_bytes());
        let size = if large { MASKED } else { len as u32 };
        head.extend_from_slice(&size.to_le_bytes());
        head.extend_from_slice(&size.to_le_bytes());
        head.extend_from_slice(&(name.len() as u16).to_le_bytes());
        head.extend_from_slice(&(if large { 20u16 } else { 0 }).to_le_bytes());
        head.extend_from_slice(name.as_bytes());
        if large {
            head.extend_from_slice(&1u16.to_le_bytes());
            head.extend_from_slice(&16u16.to_le_bytes());
            head.extend_from_slice(&len.to_le_bytes());
            head.extend_from_slice(&len.to_le_bytes());
        }
        self.put(&head)?;
        let copied = std::io::copy(&mut bytes.take(len), &mut self.out)?;
        self.written += copied;
        let mut probe = [0u8; 1];
        if copied != len || bytes.read(&mut probe)? != 0 {
            return Err(std::io::Error::other(format!(
                "{name}: not the {len} bytes announced"
            )));
        }
        self.entries.push(Entry {
            name: name.to_string(),
            crc,
            len,
            offset,
        });
        Ok(())
    }

    /// Writes the central directory; the writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        let start = self.written;
        let limit = self.zip64_from;
        let mut directory = Vec::new();
        for entry in &self.entries {
            // The zip64 extra field holds, in this order, what the classic fields mask.
            let mut extra = Vec::new();
            if entry.len >= limit {
                extra.extend_from_slice(&entry.len.to_le_bytes());
                extra.extend_from_slice(&entry.len.to_le_bytes());
            }
            if entry.offset >= limit {
                extra.extend_from_slice(&entry.offset.to_le_bytes());
            }
            let large = !extra.is_empty();
            directory.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
            directory.extend_from_slice(&version(large).to_le_bytes()); // made by
            directory.extend_from_slice(&version(large).to_le_bytes()); // needed
            directory.extend_from_slice(&0u16.to_le_bytes()); // flags
            directory.extend_from_slice(&0u16.to_le_bytes()); // stored
            directory.extend_from_slice(&DOS_TIME.to_le_bytes());
            directory.extend_from_slice(&DOS_DATE.to_le_bytes());
            directory.extend_from_slice(&entry.crc.to_le_bytes());
            let size = if entry.len >= limit {
                MASKED
            } else {
                entry.len as u32
            };
            directory.extend_from_slice(&size.to_le_bytes());
            directory.extend_from_slice(&size.to_le_bytes());
            directory.extend_from_slice(&(entry.name.len() as u16).to_le_bytes());
            let extra_len = if large { 4 + extra.len() as u16 } else { 0 };
            directory.extend_from_slice(&extra_len.to_le_bytes());
            directory.extend_from_slice(&[0; 6]); // comment length, disk, internal attributes
            directory.extend_from_slice(&[0; 4]); // external attributes
            let offset = if entry.offset >= limit {
                MASKED
            } else {
                entry.offset as u32
            };
            directory.extend_from_slice(&offset.to_le_bytes());
            directory.extend_from_slice(entry.name.as_bytes());
            if large {
                directory.extend_from_slice(&1u16.to_le_bytes());
                directory.extend_from_slice(&(extra.len() as u16).to_le_bytes());
                directory.extend_from_slice(&extra);
            }
        }
        self.put(&directory)?;
        let count = self.entries.len() as u64;
        let size = directory.len() as u64;
        let zip64 = start >= limit || size >= limit || count >= 0xFFFF;
        let mut end = Vec::new();
        if zip64 {
            let record = self.written;
            end.extend_from_slice(&0x0606_4b50u32.to_le_bytes());
            end.extend_from_slice(&44u64.to_le_bytes());
            end.extend_from_slice(&version(true).to_le_bytes());
            end.extend_from_slice(&version(true).to_le_bytes());
            end.extend_from_slice(&[0; 8]); // this disk, the directory's disk
            end.extend_from_slice(&count.to_le_bytes());
            end.extend_from_slice(&count.to_le_bytes());
            end.extend_from_slice(&size.to_le_bytes());
            end.extend_from_slice(&start.to_le_bytes());
            end.extend_from_slice(&0x0706_4b50u32.to_le_bytes());
            end.extend_from_slice(&0u32.to_le_bytes());
            end.extend_from_slice(&record.to_le_bytes());
            end.extend_from_slice(&1u32.to_le_bytes());
        }
        let short = |v: u64| if zip64 { 0xFFFF } else { v as u16 };
        let long = |v: u64| if zip64 { MASKED } else { v as u32 };
        end.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
        end.extend_from_slice(&[0; 4]); // this disk, the directory's disk
        end.extend_from_slice(&short(count).to_le_bytes());
        end.extend_from_slice(&short(count).to_le_bytes());
        end.extend_from_slice(&long(size).to_le_bytes());
        end.extend_from_slice(&long(start).to_le_bytes());
        end.extend_from_slice(&0u16.to_le_bytes()); // comment length
        self.put(&end)?;
        self.out.flush()?;
        Ok(self.out)
    }
}

/// The format version an entry needs: 2.0, or 4.5 with zip64 fields.
fn version(zip64: bool) -> u16 {
    if zip64 { 45 } else { 20 }
}

/// The CRC-32 and length of what `bytes` holds, read to its end.
pub(crate) fn crc32(bytes: &mut dyn Read) -> std::io::Result<(u32, u64)> {
    let mut hasher = crc32fast::Hasher::new();
    let mut buffer = vec![0u8; 64 << 10];
    let mut len = 0u64;
    loop {
        let n = bytes.read(&mut buffer)?;
        if n == 0 {
            return Ok((hasher.finalize(), len));
        }
        hasher.update(&buffer[..n]);
        len += n as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn archive(entries: &[(&str, Vec<u8>)], zip64_from: u64) -> Vec<u8> {
        let mut zip = StoredZip::new(Vec::new());
        zip.zip64_from = zip64_from;
        for (name, bytes) in entries {
            let (crc, len) = crc32(&mut &bytes[..]).unwrap();
            assert_eq!(len, bytes.len() as u64);
            zip.add(name, len, crc, &mut &bytes[..]).unwrap();
        }
        zip.finish().unwrap()
    }

    fn read_back(bytes: Vec<u8>) -> Vec<(String, Vec<u8>)> {
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
        (0..zip.len())
            .map(|i| {
                let mut entry = zip.by_index(i).unwrap();
                assert_eq!(entry.compression(), zip::CompressionMethod::Stored);
                let mut content = Vec::new();
                entry.read_to_end(&mut content).unwrap();
                (entry.name().to_string(), content)
            })
            .collect()
    }

    fn entries() -> Vec<(&'static str, Vec<u8>)> {
        vec![
            (
                "trial_000.txt",
                b"1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n".to_vec(),
            ),
            ("trial_001.txt", Vec::new()),
            (
                "trial_002.txt",
                (0..100_000u32).map(|i| (i * 31) as u8).collect(),
            ),
        ]
    }

    /// The zip crate reads back every entry, name and byte, classic and zip64 alike.
    #[test]
    fn an_archive_reads_back_as_written_with_and_without_zip64() {
        for zip64_from in [u64::from(MASKED), 10] {
            let got = read_back(archive(&entries(), zip64_from));
            let want: Vec<(String, Vec<u8>)> = entries()
                .into_iter()
                .map(|(n, b)| (n.to_string(), b))
                .collect();
            assert!(got == want, "zip64 from {zip64_from}");
        }
        assert!(read_back(archive(&[], u64::from(MASKED))).is_empty());
    }

    /// An entry whose reader holds other than the bytes announced is an error.
    #[test]
    fn an_entry_of_another_length_is_refused() {
        let mut zip = StoredZip::new(Vec::new());
        assert!(zip.add("a", 5, 0, &mut &b"abc"[..]).is_err());
        let mut zip = StoredZip::new(Vec::new());
        assert!(zip.add("a", 2, 0, &mut &b"abc"[..]).is_err());
    }
}
