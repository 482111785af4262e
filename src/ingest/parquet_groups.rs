//! trajectories.parquet decoded a batch of row groups at a time on a thread of its own, so that
//! memory is bounded by the writer's row groups (not the file) and decoding the next batch
//! overlaps grouping the one before.

use polars::prelude::*;
use std::io::Cursor;
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

/// Reads trajectories.parquet whole: `run` text, `particle` and `frame` integers, `t_s` and
/// `z_m` floats (or integers, read as floats, as the row-by-row path does). `None` if it cannot
/// be read or a column has another type.
pub fn read_whole(bytes: &[u8]) -> Option<DataFrame> {
    decode(bytes, None, None)
}

/// How `for_each_batch` read a file: its row groups, and the batches they were decoded in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Batches {
    pub row_groups: usize,
    pub batches: usize,
}

/// Hands `each` the file's rows in order, a row group at a time (a larger one in slices of
/// `batch_rows` rows), decoded a batch of consecutive row groups of at least `batch_rows` rows
/// at a time: the next batch is decoded on another thread meanwhile, and at most one decoded
/// batch waits. Stops at the first `Err` of `each` (returned) or at a file or batch that cannot
/// be read or has a column of another type (`Err(unreadable)`).
pub fn for_each_batch<E: Send>(
    bytes: &[u8],
    batch_rows: usize,
    unreadable: E,
    each: &mut dyn FnMut(&DataFrame) -> Result<(), E>,
) -> Result<Batches, E> {
    let batch_rows = batch_rows.max(1);
    let Some((metadata, batches)) = plan(bytes, batch_rows) else {
        return Err(unreadable);
    };
    let row_groups = metadata.row_groups.len();
    let count = batches.len();
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Option<DataFrame>>(1);
        let batches_ref = &batches;
        scope.spawn(move || {
            for rows in batches_ref {
                let df = decode(bytes, Some(metadata.clone()), Some(rows.clone()));
                let stop = df.is_none();
                // the receiver hangs up when `each` stopped
                if tx.send(df).is_err() || stop {
                    break;
                }
            }
        });
        for df in rx {
            let Some(mut df) = df else {
                return Err(unreadable);
            };
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

/// The file's metadata and its rows in batches of whole consecutive row groups, each at least
/// `batch_rows` rows but the last (one batch of no rows for a file of no row groups).
fn plan(bytes: &[u8], batch_rows: usize) -> Option<(FileMetadataRef, Vec<Range<usize>>)> {
    let read = || {
        let mut reader = ParquetReader::new(Cursor::new(bytes));
        reader.get_metadata().cloned()
    };
    let metadata = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .ok()?
        .ok()?;
    let mut batches: Vec<Range<usize>> = Vec::new();
    let mut row = 0;
    for group in &metadata.row_groups {
        let end = row + group.num_rows();
        match batches.last_mut() {
            Some(open) if open.len() < batch_rows => open.end = end,
            _ => batches.push(row..end),
        }
        row = end;
    }
    if batches.is_empty() {
        batches.push(0..0);
    }
    Some((metadata, batches))
}

/// Decodes `rows` (all rows if `None`) of the five columns, each cast to its type.
fn decode(
    bytes: &[u8],
    metadata: Option<FileMetadataRef>,
    rows: Option<Range<usize>>,
) -> Option<DataFrame> {
    let projection: Vec<String> = COLUMNS.iter().map(|(n, _)| n.to_string()).collect();
    let read = || {
        let mut reader = ParquetReader::new(Cursor::new(bytes)).with_columns(Some(projection));
        if let Some(metadata) = metadata {
            reader.set_metadata(metadata);
        }
        if let Some(rows) = rows {
            reader = reader.with_slice(Some((rows.start, rows.len())));
        }
        reader.finish()
    };
    let df = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .ok()?
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
