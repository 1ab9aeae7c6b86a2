//! The messages of an MCAP file, for any bytes: an error, never a panic or an abort.
//!
//! mcap's sans-I/O reader frames records, bounds every length it reads and checks every
//! chunk's CRC before the chunk's records are handed out. Its record parser (`parse_record`,
//! binrw) is not used: it reserves string and map lengths read from the file before checking
//! them against the record, so a damaged metadata record asks for gigabytes (found by the
//! `recording` fuzz target). Only the two records a recording's messages need, channel and
//! message, are parsed here, by hand, every length checked against the record.

use std::collections::HashMap;
use std::ops::Range;

use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

/// The largest record or decompressed chunk a recording may hold: our writer's chunks are
/// 4 MiB, so anything past this (or past a few times the file's size) is a damaged length
/// field, refused before the reader reserves memory for it.
const RECORD_LIMIT_BYTES: usize = 64 << 20;

/// The bytes an MCAP file starts and ends with.
pub(super) const MAGIC: &[u8] = b"\x89MCAP0\r\n";

const CHANNEL_OPCODE: u8 = 0x04;
const MESSAGE_OPCODE: u8 = 0x05;
const CHUNK_OPCODE: u8 = 0x06;

/// Reading options that make a damaged file an error: every length bounded, every chunk's
/// CRC checked before its records are read, the data section's CRC checked.
fn reader_options(file_len: usize) -> LinearReaderOptions {
    LinearReaderOptions::default()
        .with_record_length_limit(RECORD_LIMIT_BYTES.max(file_len.saturating_mul(4)))
        .with_prevalidate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
}

/// Every message of the file in order, as (topic, payload). `bytes` starts and ends with the
/// MCAP magic (the caller checks).
pub(super) fn messages(bytes: &[u8]) -> Result<Vec<(String, Vec<u8>)>, String> {
    let chunks = chunk_ranges(bytes)?;
    let mut reader = LinearReader::new_with_options(reader_options(bytes.len()));
    let mut at = 0usize;
    let mut topics: HashMap<u16, String> = HashMap::new();
    let mut out = Vec::new();
    while let Some(event) = reader.next_event() {
        let event = event.map_err(|e| damage_message(&describe(&e), at as u64, &chunks))?;
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let n = need.min(bytes.len() - at);
                reader.insert(n).copy_from_slice(&bytes[at..at + n]);
                reader.notify_read(n);
                at += n;
            }
            LinearReadEvent::Record { opcode, data } => {
                let damaged = |what: &str| damage_message(what, at as u64, &chunks);
                match opcode {
                    CHANNEL_OPCODE => {
                        let (id, topic) =
                            channel(data).ok_or_else(|| damaged("a bad channel record"))?;
                        topics.insert(id, topic);
                    }
                    MESSAGE_OPCODE => {
                        let (id, payload) =
                            message(data).ok_or_else(|| damaged("a bad message record"))?;
                        let topic = topics.get(&id).ok_or_else(|| {
                            damaged(&format!("a message on unknown channel {id}"))
                        })?;
                        out.push((topic.clone(), payload.to_vec()));
                    }
                    // Schemas, metadata, indexes and the summary are not needed to read
                    // messages back.
                    _ => {}
                }
            }
        }
    }
    Ok(out)
}

/// A little-endian reader over one record's bytes that never reads past them.
struct Fields<'a>(&'a [u8]);

impl<'a> Fields<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if n > self.0.len() {
            return None;
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Some(head)
    }

    fn u16(&mut self) -> Option<u16> {
        Some(u16::from_le_bytes(self.take(2)?.try_into().ok()?))
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }

    /// A u32-length-prefixed UTF-8 string.
    fn string(&mut self) -> Option<String> {
        let len = self.u32()? as usize;
        String::from_utf8(self.take(len)?.to_vec()).ok()
    }
}

/// A channel record's id and topic (the rest, encoding and metadata, is not needed).
fn channel(record: &[u8]) -> Option<(u16, String)> {
    let mut f = Fields(record);
    let id = f.u16()?;
    let _schema = f.u16()?;
    Some((id, f.string()?))
}

/// A message record's channel id and payload (after sequence, log and publish times).
fn message(record: &[u8]) -> Option<(u16, &[u8])> {
    let mut f = Fields(record);
    let id = f.u16()?;
    f.take(4 + 8 + 8)?;
    Some((id, f.0))
}

/// The byte ranges of the file's top-level chunk records, for naming the chunk a damage is
/// in. Walks the record framing (opcode, u64 length) only, checking each length against what
/// is left of the file.
pub(super) fn chunk_ranges(bytes: &[u8]) -> Result<Vec<Range<u64>>, String> {
    let end = bytes.len() - MAGIC.len();
    let mut at = MAGIC.len();
    let mut chunks = Vec::new();
    while at < end {
        if end - at < 9 {
            return Err(format!(
                "damaged recording: a record header at byte {at} is cut off"
            ));
        }
        let opcode = bytes[at];
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[at + 1..at + 9]);
        let len = u64::from_le_bytes(len);
        let next = (at as u64 + 9)
            .checked_add(len)
            .filter(|&n| n <= end as u64);
        let Some(next) = next else {
            return Err(format!(
                "damaged recording: the record at byte {at} claims {len} bytes, past the end of the file"
            ));
        };
        if opcode == CHUNK_OPCODE {
            let k = chunks.len();
            check_chunk(&bytes[at + 9..next as usize])
                .map_err(|e| format!("damaged recording: chunk {k} (bytes {at}..{next}): {e}"))?;
            chunks.push(at as u64..next);
        }
        at = next as usize;
    }
    Ok(chunks)
}

/// An error of mcap's reader in words.
fn describe(error: &mcap::McapError) -> String {
    match error {
        mcap::McapError::BadChunkCrc { saved, calculated } => {
            format!("its CRC does not match (saved {saved:#010x}, computed {calculated:#010x})")
        }
        other => other.to_string(),
    }
}

/// Checks a chunk record's header before mcap's reader trusts it: a CRC to check the records
/// against (our writer always sets one; 0 would let damage through), a compression string
/// and a records length that fit the record, and, for an uncompressed chunk, records that
/// each fit inside it (mcap's reader subtracts their lengths unchecked).
fn check_chunk(body: &[u8]) -> Result<(), String> {
    let mut f = Fields(body);
    let header = (|| {
        f.take(8 + 8 + 8)?;
        let crc = f.u32()?;
        let compression = f.string()?;
        let len = u64::from_le_bytes(f.take(8)?.try_into().ok()?);
        Some((crc, compression, len))
    })();
    let Some((crc, compression, len)) = header else {
        return Err("its header is cut off".into());
    };
    if crc == 0 {
        return Err("it has no CRC to check its records against".into());
    }
    if len > f.0.len() as u64 {
        return Err(format!("it claims {len} bytes of records, past its end"));
    }
    if compression.is_empty() {
        let mut records = Fields(&f.0[..len as usize]);
        while !records.0.is_empty() {
            let fits = records.take(1).and_then(|_| records.take(8)).and_then(|l| {
                let l = u64::from_le_bytes(l.try_into().ok()?);
                records.take(usize::try_from(l).ok()?)
            });
            if fits.is_none() {
                return Err("a record inside runs past the chunk".into());
            }
        }
    }
    Ok(())
}

/// What went wrong at reader position `at`, naming the chunk it falls in.
fn damage_message(what: &str, at: u64, chunks: &[Range<u64>]) -> String {
    match chunks.iter().position(|c| c.start < at && at <= c.end) {
        Some(k) => format!(
            "damaged recording: chunk {k} of {} (bytes {}..{}): {what}",
            chunks.len(),
            chunks[k].start,
            chunks[k].end
        ),
        None => format!("damaged recording near byte {at}: {what}"),
    }
}
