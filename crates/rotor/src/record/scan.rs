//! A tolerant, bounded scan of an MCAP file's records, front to back.
//!
//! The reader ([`super::reader`]) needs three things the `mcap` crate's readers do not
//! give on damaged input: to go on past a damaged chunk (every point is its own chunk, so
//! one flipped byte should cost one point, not the file); never to allocate more than the
//! file holds (a hostile length field must not become a multi-exabyte allocation); and to
//! stream (memory bounded by the largest record, not the file's size). So the records are
//! parsed here, with every length checked against the bytes that are actually there:
//!
//! - a top-level record whose length runs past the end of the file is either a cut (no
//!   further record follows) or a damaged length: the scan then searches forward for the
//!   next chunk (its header is self-describing: opcode, record length, compression
//!   `zstd`, and a compressed size that must agree with the record length) or the
//!   data-end record, and reports the bytes in between as damaged;
//! - a chunk is checked as a whole before any of its records is handed on: its lengths,
//!   its decompressed size (at most [`MAX_RECORD_BYTES`] and 64 times the compressed
//!   size plus 1 MiB), its CRC, and every record inside; a chunk that fails any check is
//!   reported as damaged and skipped;
//! - records outside chunks (attachments, metadata, the summary section) are parsed with
//!   the same bounds; one that fails is reported and skipped.
//!
//! The MCAP layout is that of the specification (mcap.dev/spec): magic, then records of
//! `opcode: u8, length: u64, body`; strings and byte arrays carry `u32` (`u64` for
//! attachment data) length prefixes; maps a `u32` byte length.

use std::collections::BTreeMap;
use std::io::{self, Read, Seek, SeekFrom};

/// Largest record (or decompressed chunk) the scan accepts: 512 MiB. tmrotor writes one
/// point per chunk (tens to hundreds of kB); a larger length is damage, not data.
pub const MAX_RECORD_BYTES: u64 = 512 << 20;

const MAGIC: &[u8] = b"\x89MCAP0\r\n";
const OP_FOOTER: u8 = 0x02;
const OP_SCHEMA: u8 = 0x03;
const OP_CHANNEL: u8 = 0x04;
const OP_MESSAGE: u8 = 0x05;
const OP_CHUNK: u8 = 0x06;
const OP_ATTACHMENT: u8 = 0x09;
const OP_STATISTICS: u8 = 0x0B;
const OP_METADATA: u8 = 0x0C;
const OP_DATA_END: u8 = 0x0F;

/// One record the scan hands on.
#[derive(Debug)]
pub enum Item<'a> {
    Schema {
        id: u16,
        name: String,
        encoding: String,
    },
    Channel {
        id: u16,
        schema_id: u16,
        topic: String,
        encoding: String,
    },
    Message {
        channel_id: u16,
        data: &'a [u8],
    },
    Attachment {
        name: String,
        data: &'a [u8],
    },
    Metadata {
        name: String,
        map: BTreeMap<String, String>,
    },
    /// The summary's message count per channel and its chunk count.
    Statistics {
        chunk_count: u32,
        channel_message_counts: BTreeMap<u16, u64>,
    },
    DataEnd,
    Footer,
}

/// What the scan found wrong with the file's structure.
#[derive(Debug, Default)]
pub struct ScanReport {
    /// Damaged stretches that were skipped, each with its byte offset and the reason.
    pub damage: Vec<String>,
    /// Chunks skipped as damaged.
    pub damaged_chunks: usize,
    /// Where and why the file ends in the middle of a record.
    pub cut: Option<String>,
    /// The file ends with the MCAP magic bytes.
    pub end_magic: bool,
    /// Chunks read whole.
    pub chunks: usize,
}

/// Why the scan could not start.
#[derive(Debug)]
pub enum ScanError {
    Io(io::Error),
    /// Not an MCAP file (no magic at the start).
    NotMcap(String),
}

/// The little-endian `u64` at `b[at..at + 8]` (the caller has checked the length).
fn le_u64(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// A bounded little-endian cursor over a record body.
struct Cur<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Cur<'a> {
    fn new(b: &'a [u8]) -> Self {
        Self { b, at: 0 }
    }
    fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], String> {
        let left = (self.b.len() - self.at) as u64;
        if n > left {
            return Err(format!(
                "{what}: length {n} exceeds the {left} bytes left in the record"
            ));
        }
        let s = &self.b[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn u16(&mut self, what: &str) -> Result<u16, String> {
        let s = self.take(2, what)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let s = self.take(4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(le_u64(self.take(8, what)?, 0))
    }
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)?;
        let s = self.take(u64::from(n), what)?;
        String::from_utf8(s.to_vec()).map_err(|_| format!("{what}: not UTF-8"))
    }
    fn string_map(&mut self, what: &str) -> Result<BTreeMap<String, String>, String> {
        let n = self.u32(what)?;
        let mut inner = Cur::new(self.take(u64::from(n), what)?);
        let mut map = BTreeMap::new();
        while inner.at < inner.b.len() {
            let k = inner.string(what)?;
            let v = inner.string(what)?;
            map.insert(k, v);
        }
        Ok(map)
    }
    fn rest(&mut self) -> &'a [u8] {
        let s = &self.b[self.at..];
        self.at = self.b.len();
        s
    }
}

/// Parses a record that may appear inside a chunk (schema, channel, message).
fn chunk_item(op: u8, body: &[u8]) -> Result<Option<Item<'_>>, String> {
    let mut c = Cur::new(body);
    Ok(match op {
        OP_SCHEMA => {
            let id = c.u16("schema id")?;
            let name = c.string("schema name")?;
            let encoding = c.string("schema encoding")?;
            let n = c.u32("schema data")?;
            c.take(u64::from(n), "schema data")?;
            Some(Item::Schema { id, name, encoding })
        }
        OP_CHANNEL => {
            let id = c.u16("channel id")?;
            let schema_id = c.u16("channel schema id")?;
            let topic = c.string("channel topic")?;
            let encoding = c.string("channel message encoding")?;
            c.string_map("channel metadata")?;
            Some(Item::Channel {
                id,
                schema_id,
                topic,
                encoding,
            })
        }
        OP_MESSAGE => {
            let channel_id = c.u16("message channel id")?;
            c.u32("message sequence")?;
            c.u64("message log time")?;
            c.u64("message publish time")?;
            Some(Item::Message {
                channel_id,
                data: c.rest(),
            })
        }
        _ => None,
    })
}

/// Parses a top-level record other than a chunk.
fn top_item(op: u8, body: &[u8]) -> Result<Option<Item<'_>>, String> {
    let mut c = Cur::new(body);
    Ok(match op {
        OP_SCHEMA | OP_CHANNEL | OP_MESSAGE => chunk_item(op, body)?,
        OP_ATTACHMENT => {
            c.u64("attachment log time")?;
            c.u64("attachment create time")?;
            let name = c.string("attachment name")?;
            c.string("attachment media type")?;
            let n = c.u64("attachment data")?;
            let header_len = c.at;
            let data = c.take(n, "attachment data")?;
            let crc = c.u32("attachment crc")?;
            if crc != 0 {
                let got = crc32fast::hash(&body[..header_len + data.len()]);
                if got != crc {
                    return Err(format!(
                        "attachment {name:?}: CRC {got:#010x}, recorded {crc:#010x}"
                    ));
                }
            }
            Some(Item::Attachment { name, data })
        }
        OP_METADATA => {
            let name = c.string("metadata name")?;
            let map = c.string_map("metadata")?;
            Some(Item::Metadata { name, map })
        }
        OP_STATISTICS => {
            c.u64("statistics message count")?;
            c.u16("statistics schema count")?;
            c.u32("statistics channel count")?;
            c.u32("statistics attachment count")?;
            c.u32("statistics metadata count")?;
            let chunk_count = c.u32("statistics chunk count")?;
            c.u64("statistics start time")?;
            c.u64("statistics end time")?;
            let n = c.u32("statistics channel message counts")?;
            let mut inner = Cur::new(c.take(u64::from(n), "statistics channel message counts")?);
            let mut channel_message_counts = BTreeMap::new();
            while inner.at < inner.b.len() {
                let id = inner.u16("statistics channel id")?;
                let count = inner.u64("statistics message count")?;
                channel_message_counts.insert(id, count);
            }
            Some(Item::Statistics {
                chunk_count,
                channel_message_counts,
            })
        }
        OP_DATA_END => Some(Item::DataEnd),
        OP_FOOTER => Some(Item::Footer),
        _ => None,
    })
}

/// Checks and unpacks a chunk: returns its decompressed records, or why it is damaged.
fn unpack_chunk(body: &[u8]) -> Result<Vec<u8>, String> {
    let mut c = Cur::new(body);
    c.u64("chunk start time")?;
    c.u64("chunk end time")?;
    let uncompressed_size = c.u64("chunk uncompressed size")?;
    let crc = c.u32("chunk crc")?;
    let compression = c.string("chunk compression")?;
    let compressed_size = c.u64("chunk compressed size")?;
    let data = c.rest();
    if compressed_size != data.len() as u64 {
        return Err(format!(
            "compressed size {compressed_size} disagrees with the record ({} bytes)",
            data.len()
        ));
    }
    let bound = (64 * compressed_size)
        .saturating_add(1 << 20)
        .min(MAX_RECORD_BYTES);
    if uncompressed_size > bound {
        return Err(format!(
            "decompressed size {uncompressed_size} is implausible for {compressed_size} compressed bytes"
        ));
    }
    let records = match compression.as_str() {
        "" => data.to_vec(),
        "zstd" => zstd::bulk::decompress(data, uncompressed_size as usize)
            .map_err(|e| format!("zstd: {e}"))?,
        other => return Err(format!("compression {other:?} is not one tmrotor reads")),
    };
    if records.len() as u64 != uncompressed_size {
        return Err(format!(
            "decompressed to {} bytes, recorded {uncompressed_size}",
            records.len()
        ));
    }
    if crc != 0 {
        let got = crc32fast::hash(&records);
        if got != crc {
            return Err(format!(
                "CRC {got:#010x} of the decompressed records, recorded {crc:#010x}"
            ));
        }
    }
    Ok(records)
}

/// Splits a chunk's decompressed records into items, or says why it cannot.
fn chunk_items(records: &[u8]) -> Result<Vec<Item<'_>>, String> {
    let mut items = Vec::new();
    let mut c = Cur::new(records);
    while c.at < records.len() {
        let op = c.take(1, "record opcode")?[0];
        let len = c.u64("record length")?;
        let body = c.take(len, "record")?;
        if let Some(item) = chunk_item(op, body)? {
            items.push(item);
        }
    }
    Ok(items)
}

/// Whether `head` (at least 54 bytes: up to the compressed size) starts a zstd chunk whose record fits in `left`
/// bytes: opcode, record length, compression `zstd`, compressed size = record length − 44.
fn chunk_signature(head: &[u8], left: u64) -> bool {
    if head.len() < 54 || head[0] != OP_CHUNK {
        return false;
    }
    let len = le_u64(head, 1);
    len >= 44
        && len.saturating_add(9) <= left
        && &head[37..45] == b"\x04\x00\x00\x00zstd"
        && le_u64(head, 45) == len - 44
}

/// Whether `head` starts a data-end record (opcode, length 4).
fn data_end_signature(head: &[u8]) -> bool {
    head.len() >= 9 && head[0] == OP_DATA_END && head[1..9] == 4u64.to_le_bytes()
}

/// Scans `r` (of `size` bytes) and hands every intact record to `visit`, in file order.
/// `visit` returning an error stops the scan with it.
pub fn scan<R: Read + Seek, E>(
    mut r: R,
    size: u64,
    mut visit: impl FnMut(Item<'_>) -> Result<(), E>,
) -> Result<Result<ScanReport, E>, ScanError> {
    let mut magic = [0u8; 8];
    let n = read_up_to(&mut r, &mut magic).map_err(ScanError::Io)?;
    if n < 8 || magic != MAGIC {
        return Err(ScanError::NotMcap(format!(
            "it does not start with the MCAP magic bytes ({size} bytes long)"
        )));
    }
    let mut report = ScanReport::default();
    let untrusted_from = check_end(&mut r, size, &mut report)?;
    let summary_notes = report.damage.len();
    let mut pos = 8u64;
    let mut body = Vec::new();
    // CRC of the data section (from the start of the file to the data-end record), as the
    // data-end record states it; only meaningful while every record was read in sequence.
    let mut data_crc = crc32fast::Hasher::new();
    data_crc.update(MAGIC);
    let mut in_sequence = true;
    let mut after_data_end = false;
    while pos < size {
        // The trailing magic of a finished file, or a summary section that is damaged.
        if (report.end_magic && pos == size - 8) || untrusted_from.is_some_and(|u| pos >= u) {
            break;
        }
        let left = size - pos;
        if left < 9 {
            report.cut = Some(format!(
                "byte {pos}: {left} bytes, less than a record header"
            ));
            break;
        }
        r.seek(SeekFrom::Start(pos)).map_err(ScanError::Io)?;
        let mut head = [0u8; 9];
        r.read_exact(&mut head).map_err(ScanError::Io)?;
        let op = head[0];
        let len = le_u64(&head, 1);
        let fits = len <= left - 9;
        // tmrotor writes every schema, channel and message inside a (checked) chunk; one of
        // them outside a chunk in the data section, or an opcode MCAP does not define,
        // means the scan is reading from a damaged place.
        let stray = !(0x01..=0x0F).contains(&op)
            || (!after_data_end && matches!(op, OP_SCHEMA | OP_CHANNEL | OP_MESSAGE));
        if !fits || len > MAX_RECORD_BYTES || stray {
            let why = if stray {
                format!("record opcode {op:#04x} where tmrotor writes none")
            } else if fits {
                format!("record length {len} is implausible")
            } else {
                format!("record length {len} runs past the end of the file ({left} bytes left)")
            };
            in_sequence = false;
            match skip_damage(&mut r, &mut report, pos, size, &why, fits)? {
                Some(next) => {
                    pos = next;
                    continue;
                }
                None => break,
            }
        }
        body.clear();
        body.resize(len as usize, 0);
        r.read_exact(&mut body).map_err(ScanError::Io)?;
        let next = pos + 9 + len;
        if op == OP_DATA_END
            && in_sequence
            && report.damage.len() == summary_notes
            && body.len() >= 4
        {
            let stated = u32::from_le_bytes([body[0], body[1], body[2], body[3]]);
            let got = data_crc.clone().finalize();
            if stated != 0 && stated != got {
                report.damage.push(format!(
                    "data section: CRC {got:#010x}, recorded {stated:#010x} (a byte outside the chunks' own checks was altered)"
                ));
            }
        }
        after_data_end |= op == OP_DATA_END;
        if op != OP_DATA_END && in_sequence {
            data_crc.update(&head);
            data_crc.update(&body);
        }
        if let Err(e) = hand_on(op, &body, pos, &mut report, &mut visit) {
            return Ok(Err(e));
        }
        pos = next;
    }
    Ok(Ok(report))
}

/// Checks the end of `r` (of `size` bytes): whether it ends with the MCAP magic
/// (`report.end_magic`), and then the summary section against the footer's CRC. Returns
/// where the summary section starts when it is damaged (its records are not to be used),
/// the damage noted in `report`.
fn check_end<R: Read + Seek>(
    r: &mut R,
    size: u64,
    report: &mut ScanReport,
) -> Result<Option<u64>, ScanError> {
    if size >= 16 {
        r.seek(SeekFrom::Start(size - 8)).map_err(ScanError::Io)?;
        let mut tail = [0u8; 8];
        r.read_exact(&mut tail).map_err(ScanError::Io)?;
        report.end_magic = tail == MAGIC;
    }
    // The summary section is checked against the footer's CRC before it is read: its
    // records (channel definitions among them) are used only when it is intact.
    let mut untrusted_from = None;
    const FOOTER_LEN: u64 = 1 + 8 + 20;
    if report.end_magic && size >= 8 + FOOTER_LEN + 8 {
        let footer_pos = size - 8 - FOOTER_LEN;
        r.seek(SeekFrom::Start(footer_pos)).map_err(ScanError::Io)?;
        let mut footer = [0u8; FOOTER_LEN as usize];
        r.read_exact(&mut footer).map_err(ScanError::Io)?;
        if footer[0] == OP_FOOTER && footer[1..9] == 20u64.to_le_bytes() {
            let body = &footer[9..];
            if let Some(why) = check_summary_crc(r, body, footer_pos).map_err(ScanError::Io)? {
                report
                    .damage
                    .push(format!("{why}; the summary section is not used"));
                untrusted_from = Some(le_u64(body, 0));
            }
        }
    }
    Ok(untrusted_from)
}

/// Skips a damaged record header at `pos` (`why` it is; `fits`: its length stays inside
/// the file of `size` bytes) to the next chunk or data-end record found, noting the
/// skipped bytes in `report`; with nothing found after it, notes why the scan stops there
/// (damage when the length fitted, a cut otherwise). Returns where the scan goes on.
fn skip_damage<R: Read + Seek>(
    r: &mut R,
    report: &mut ScanReport,
    pos: u64,
    size: u64,
    why: &str,
    fits: bool,
) -> Result<Option<u64>, ScanError> {
    match resync(r, pos + 1, size).map_err(ScanError::Io)? {
        Some(next) => {
            report.damage.push(format!(
                "bytes {pos}–{next}: {why}; skipped to the next record found"
            ));
            Ok(Some(next))
        }
        None if fits => {
            report
                .damage
                .push(format!("byte {pos}: {why}; nothing readable follows"));
            Ok(None)
        }
        None => {
            report.cut = Some(format!("byte {pos}: {why}"));
            Ok(None)
        }
    }
}

/// Hands the intact items of the record at `pos` (opcode `op`, `body`) to `visit`: a
/// chunk's records once the whole chunk is checked, or another top-level record; a damaged
/// chunk or record is counted and noted in `report` and skipped. `visit` returning an
/// error stops with it.
fn hand_on<E>(
    op: u8,
    body: &[u8],
    pos: u64,
    report: &mut ScanReport,
    visit: &mut impl FnMut(Item<'_>) -> Result<(), E>,
) -> Result<(), E> {
    if op == OP_CHUNK {
        let unpacked = unpack_chunk(body);
        let items = unpacked
            .as_deref()
            .map_err(Clone::clone)
            .and_then(chunk_items);
        match items {
            Ok(items) => {
                report.chunks += 1;
                for item in items {
                    visit(item)?;
                }
            }
            Err(why) => {
                report.damaged_chunks += 1;
                report
                    .damage
                    .push(format!("chunk at byte {pos}: {why}; skipped"));
            }
        }
    } else {
        match top_item(op, body) {
            Ok(Some(item)) => visit(item)?,
            Ok(None) => {}
            Err(why) => report
                .damage
                .push(format!("record {op:#04x} at byte {pos}: {why}; skipped")),
        }
    }
    Ok(())
}

/// Checks the summary section's CRC stated in the footer (`body`, at `footer_pos`): the
/// CRC of every byte from the summary's start through the footer's `summary_offset_start`.
fn check_summary_crc<R: Read + Seek>(
    r: &mut R,
    body: &[u8],
    footer_pos: u64,
) -> io::Result<Option<String>> {
    let summary_start = le_u64(body, 0);
    let stated = u32::from_le_bytes([body[16], body[17], body[18], body[19]]);
    if stated == 0 || summary_start == 0 {
        return Ok(None);
    }
    let end = footer_pos + 1 + 8 + 16;
    if summary_start >= footer_pos {
        return Ok(Some(format!(
            "footer: summary start {summary_start} is not before the footer at byte {footer_pos}"
        )));
    }
    r.seek(SeekFrom::Start(summary_start))?;
    let mut hasher = crc32fast::Hasher::new();
    let mut left = end - summary_start;
    let mut buf = vec![0u8; 1 << 16];
    while left > 0 {
        let n = (left as usize).min(buf.len());
        r.read_exact(&mut buf[..n])?;
        hasher.update(&buf[..n]);
        left -= n as u64;
    }
    let got = hasher.finalize();
    Ok((got != stated)
        .then(|| format!("summary section: CRC {got:#010x}, recorded {stated:#010x}")))
}

/// The offset of the next chunk or data-end record at or after `from`, if any.
fn resync<R: Read + Seek>(r: &mut R, from: u64, size: u64) -> io::Result<Option<u64>> {
    const WINDOW: usize = 1 << 20;
    const HEAD: usize = 54;
    let mut start = from;
    let mut buf = vec![0u8; WINDOW + HEAD];
    while start < size {
        r.seek(SeekFrom::Start(start))?;
        let n = read_up_to(r, &mut buf)?;
        if n == 0 {
            break;
        }
        for i in 0..n {
            let at = start + i as u64;
            let head = &buf[i..n];
            if chunk_signature(head, size - at) || data_end_signature(head) {
                return Ok(Some(at));
            }
        }
        if start + n as u64 >= size || n <= HEAD {
            break;
        }
        start += (n - HEAD) as u64;
    }
    Ok(None)
}

fn read_up_to<R: Read>(r: &mut R, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hostile_string_length_is_refused_without_allocating() {
        let mut body = vec![1u8, 0];
        body.extend_from_slice(&u32::MAX.to_le_bytes());
        let err = chunk_item(OP_SCHEMA, &body).expect_err("hostile");
        assert!(err.contains("exceeds"), "{err}");
    }

    #[test]
    fn an_implausible_decompressed_size_is_damage() {
        let mut body = Vec::new();
        body.extend_from_slice(&0u64.to_le_bytes());
        body.extend_from_slice(&0u64.to_le_bytes());
        body.extend_from_slice(&(1u64 << 58).to_le_bytes());
        body.extend_from_slice(&0u32.to_le_bytes());
        body.extend_from_slice(&4u32.to_le_bytes());
        body.extend_from_slice(b"zstd");
        body.extend_from_slice(&3u64.to_le_bytes());
        body.extend_from_slice(&[1, 2, 3]);
        let err = unpack_chunk(&body).expect_err("hostile");
        assert!(err.contains("implausible"), "{err}");
    }
}
