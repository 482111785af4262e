//! trajectories.parquet read once, in order, and decoded a batch of row groups at a time on a
//! thread of its own, so that memory is bounded by the writer's row groups (not the file) and
//! reading and decoding the next batch overlaps grouping the one before.

use super::csv_pieces::Stop;
use super::parquet_pages;
use super::table::guarded;
use polars::prelude::*;
use std::io::{Cursor, Read};
use std::ops::Range;

/// The trajectory columns and their types.
pub const COLUMNS: [(&str, DataType); 5] = [
    ("run", DataType::String),
    ("particle", DataType::Int64),
    ("frame", DataType::Int64),
    ("t_s", DataType::Float64),
    ("z_m", DataType::Float64),
];

/// Bytes of decoded columns per row, roughly (four 8-byte numbers and a run id's view): a piece
/// of `chunk_bytes` of CSV is about as many rows as a batch of `chunk_bytes / ROW_BYTES` rows
/// (262,144 rows for the 8 MB pieces).
pub const ROW_BYTES: usize = 32;

/// Why a Parquet file is left to the whole read, which names the problem.
const PROBLEM: &str = "a Parquet file the batched read cannot take (the whole read says why)";

/// A trajectories file as the streamed read gets it: one pass in order (`Read`, which may check
/// what it gives against the key, and fails at the end if it does not match), and reads at an
/// offset apart from that pass, for a Parquet file's footer.
pub trait Source: Read + Send {
    /// The file's length.
    fn file_len(&self) -> std::io::Result<u64>;
    /// `buf.len()` bytes from `offset`; the pass in order does not move.
    fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()>;
}

/// A file's bytes in memory as a `Source`.
pub struct InMemory<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl<'b> InMemory<'b> {
    pub fn new(bytes: &'b [u8]) -> Self {
        InMemory { bytes, at: 0 }
    }
}

impl Read for InMemory<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (&self.bytes[self.at..]).read(buf)?;
        self.at += n;
        Ok(n)
    }
}

impl Source for InMemory<'_> {
    fn file_len(&self) -> std::io::Result<u64> {
        Ok(self.bytes.len() as u64)
    }

    fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        let start = usize::try_from(offset).unwrap_or(usize::MAX);
        match self.bytes.get(start..start.saturating_add(buf.len())) {
            Some(part) => {
                buf.copy_from_slice(part);
                Ok(())
            }
            None => Err(std::io::ErrorKind::UnexpectedEof.into()),
        }
    }
}

/// Reads trajectories.parquet whole: `run` text, `particle` and `frame` integers, `t_s` and
/// `z_m` floats (or integers, read as floats, as the row-by-row path does). `None` if it cannot
/// be read or a column has another type.
pub fn read_whole(bytes: &[u8]) -> Option<DataFrame> {
    let metadata = metadata_of(bytes)?;
    let rows = 0..metadata.num_rows;
    decode(bytes, metadata, rows)
}

/// How `for_each_batch` read a file: its row groups, and the batches they were decoded in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Batches {
    pub row_groups: usize,
    pub batches: usize,
}

/// One batch: its rows, and where the bytes of the file that hold them end (they start where
/// the batch before ended, so that the batches' bytes cover the file in order up to the footer).
struct Batch {
    rows: Range<usize>,
    end: u64,
}

/// Hands `each` the file's rows in order, a row group at a time (a larger one in slices of
/// `batch_rows` rows), decoded a batch of consecutive row groups of at least `batch_rows` rows
/// at a time. The footer is read first (`Source::read_at`), to plan the batches; then the file
/// is read once in order on another thread, each batch's bytes into a buffer of their own,
/// decoded there while `each` works on the batch before (at most one decoded batch waits), and
/// at the end the footer read first must be the one read in order (and the reader's check must
/// pass): so every byte decoded is a byte checked. Stops at the first `Err` of `each`
/// (returned), at a read that fails or a file that changed (`Stop::Read`), or at a file or batch
/// that cannot be decoded or has a column of another type, or a layout with row groups out of
/// file order (`Stop::Reason`).
pub fn for_each_batch(
    source: &mut dyn Source,
    batch_rows: usize,
    each: &mut dyn FnMut(&DataFrame) -> Result<(), Stop>,
) -> Result<Batches, Stop> {
    let batch_rows = batch_rows.max(1);
    let len = source.file_len().map_err(Stop::Read)?;
    let (footer_at, footer) = read_footer(source, len)?;
    let metadata = metadata(len, footer_at, &footer).ok_or(PROBLEM)?;
    let batches = plan(&metadata, batch_rows, footer_at).ok_or(PROBLEM)?;
    let row_groups = metadata.row_groups.len();
    let count = batches.len();
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Result<DataFrame, Stop>>(1);
        let (metadata, batches) = (&metadata, &batches);
        let footer = &footer;
        scope.spawn(move || {
            let mut at = 0;
            for batch in batches {
                let df = read_to(source, len, &mut at, batch.end).and_then(|buffer| {
                    decode(&buffer, metadata.clone(), batch.rows.clone())
                        .ok_or(Stop::Reason(PROBLEM))
                });
                let stop = df.is_err();
                // the receiver hangs up when `each` stopped
                if tx.send(df).is_err() || stop {
                    return;
                }
            }
            if let Err(stop) = read_rest(source, at, len, footer) {
                let _ = tx.send(Err(stop));
            }
        });
        for df in rx {
            let mut df = df?;
            if df.height() == 0 {
                each(&df)?;
            }
            // a row group is a chunk of each column: handed on as it is, not copied into one
            for part in df.split_chunks() {
                let mut start = 0;
                while start < part.height() {
                    each(&part.slice(start as i64, batch_rows))?;
                    start += batch_rows;
                }
            }
        }
        Ok(Batches {
            row_groups,
            batches: count,
        })
    })
}

/// The footer (the file metadata, its length and the closing magic) and where it starts.
fn read_footer(source: &dyn Source, len: u64) -> Result<(u64, Vec<u8>), Stop> {
    if len < 12 {
        return Err(PROBLEM.into());
    }
    let mut end = [0u8; 8];
    source.read_at(&mut end, len - 8).map_err(Stop::Read)?;
    let meta_len = u64::from(u32::from_le_bytes([end[0], end[1], end[2], end[3]]));
    if &end[4..] != b"PAR1" || meta_len + 12 > len {
        return Err(PROBLEM.into());
    }
    let at = len - 8 - meta_len;
    let mut footer = vec![0u8; (len - at) as usize];
    source.read_at(&mut footer, at).map_err(Stop::Read)?;
    Ok((at, footer))
}

/// A buffer as long as the file, all zeros but for what is written into it: fresh pages from
/// the kernel, so only the pages written take memory (a heap allocation of the same size may
/// be dirty and need zeroing first).
fn sparse_file(len: u64) -> std::io::Result<memmap2::MmapMut> {
    let len = usize::try_from(len).map_err(|_| std::io::ErrorKind::OutOfMemory)?;
    memmap2::MmapMut::map_anon(len.max(1))
}

/// The file's metadata, from its footer alone.
fn metadata(len: u64, footer_at: u64, footer: &[u8]) -> Option<FileMetadataRef> {
    let mut file = sparse_file(len).ok()?;
    file[footer_at as usize..len as usize].copy_from_slice(footer);
    metadata_of(&file[..len as usize])
}

/// The metadata in the footer of a file's bytes (`None` if it cannot be read; the whole read
/// names the problem).
fn metadata_of(bytes: &[u8]) -> Option<FileMetadataRef> {
    guarded(|| {
        ParquetReader::new(Cursor::new(bytes))
            .get_metadata()
            .cloned()
    })
    .ok()
}

/// The file's rows in batches of whole consecutive row groups, each at least `batch_rows` rows
/// but the last (one batch of no rows for a file of no row groups), with where their bytes end;
/// `None` when the row groups' bytes are not in file order before the footer.
fn plan(metadata: &FileMetadata, batch_rows: usize, footer_at: u64) -> Option<Vec<Batch>> {
    let mut batches: Vec<Batch> = Vec::new();
    let (mut row, mut byte) = (0, 0);
    for group in &metadata.row_groups {
        let bytes = group.full_byte_range();
        if bytes.start < byte || bytes.end < bytes.start || bytes.end > footer_at {
            return None;
        }
        let end = row + group.num_rows();
        match batches.last_mut() {
            Some(open) if open.rows.len() < batch_rows => {
                open.rows.end = end;
                open.end = bytes.end;
            }
            _ => batches.push(Batch {
                rows: row..end,
                end: bytes.end,
            }),
        }
        (row, byte) = (end, bytes.end);
    }
    if batches.is_empty() {
        batches.push(Batch { rows: 0..0, end: 0 });
    }
    Some(batches)
}

/// Reads the file in order from `*at` up to `end` into a sparse buffer of the file's length (at
/// their offsets, as the decoder wants them), and moves `*at` on.
fn read_to(
    source: &mut dyn Source,
    len: u64,
    at: &mut u64,
    end: u64,
) -> Result<memmap2::MmapMut, Stop> {
    let mut buffer = sparse_file(len).map_err(Stop::Read)?;
    match source.read_exact(&mut buffer[*at as usize..end as usize]) {
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Err(changed()),
        Err(e) => return Err(Stop::Read(e)),
        Ok(()) => {}
    }
    *at = end;
    Ok(buffer)
}

/// Reads the rest of the file in order, from `at`: it must be the footer read first, up to
/// the end of the file (the read that finds the end is where the reader checks the content).
fn read_rest(source: &mut dyn Source, at: u64, len: u64, footer: &[u8]) -> Result<(), Stop> {
    let mut rest = Vec::new();
    source.read_to_end(&mut rest).map_err(Stop::Read)?;
    if at + rest.len() as u64 != len || !rest.ends_with(footer) {
        return Err(changed());
    }
    Ok(())
}

/// The file is not as it was when its footer was read.
fn changed() -> Stop {
    Stop::Read(std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        "the Parquet file changed while it was read; run again",
    ))
}

/// Decodes `rows` of the five columns, each cast to its type, once their pages' headers are
/// found sound (`parquet_pages`: a damaged header would make polars abort the process).
fn decode(bytes: &[u8], metadata: FileMetadataRef, rows: Range<usize>) -> Option<DataFrame> {
    let names = COLUMNS.map(|(n, _)| n);
    if !parquet_pages::sound(bytes, &metadata, rows.clone(), Some(&names)) {
        return None;
    }
    let projection: Vec<String> = names.iter().map(|n| n.to_string()).collect();
    let df = guarded(|| {
        let mut reader = ParquetReader::new(Cursor::new(bytes)).with_columns(Some(projection));
        reader.set_metadata(metadata);
        reader.with_slice(Some((rows.start, rows.len()))).finish()
    })
    .ok()?;
    let mut columns = Vec::with_capacity(COLUMNS.len());
    for (name, dtype) in &COLUMNS {
        let c = df.column(name).ok()?;
        let fits = match dtype {
            DataType::String => c.dtype() == &DataType::String,
            DataType::Int64 => c.dtype().is_integer(),
            _ => {
                c.dtype().is_integer() || matches!(c.dtype(), DataType::Float32 | DataType::Float64)
            }
        };
        if !fits {
            return None;
        }
        columns.push(c.cast(dtype).ok()?);
    }
    DataFrame::new(df.height(), columns).ok()
}
