//! A Parquet file's page headers checked before polars decodes the pages: polars casts a
//! header's 32-bit counts to `usize`, so a damaged header with a negative count made its decoder
//! ask for about 2^61 bytes, and a failed allocation aborts the process (no error, no panic).

use polars::prelude::FileMetadata;
use polars_parquet_format::thrift::protocol::TCompactInputProtocol;
use polars_parquet_format::{PageHeader, PageType};
use std::ops::Range;

/// Whether the page headers of `columns` (all if `None`) are sound in every row group that holds
/// a row of `rows` (row numbers of the whole file): each column chunk lies in `file` (the file's
/// bytes at their offsets) and holds one value a row (a nested column: no negative count), and
/// its pages, read in order from its start as the decoder reads them, have no negative size or
/// count, lie inside the chunk, and hold exactly the chunk's values (a dictionary no more
/// entries than values).
pub fn sound(
    file: &[u8],
    metadata: &FileMetadata,
    rows: Range<usize>,
    columns: Option<&[&str]>,
) -> bool {
    let mut first: usize = 0;
    for group in &metadata.row_groups {
        let group_rows = first..first.saturating_add(group.num_rows());
        first = group_rows.end;
        if group_rows.end <= rows.start || group_rows.start >= rows.end {
            continue;
        }
        for column in group.parquet_columns() {
            let path = &column.descriptor().path_in_schema;
            if columns.is_some_and(|names| path.len() != 1 || !names.contains(&path[0].as_str())) {
                continue;
            }
            let range = column.byte_range();
            let chunk = usize::try_from(range.start)
                .ok()
                .zip(usize::try_from(range.end).ok())
                .and_then(|(start, end)| file.get(start..end));
            let values = usize::try_from(column.num_values())
                .ok()
                .filter(|&n| path.len() != 1 || n == group.num_rows());
            match (chunk, values) {
                (Some(chunk), Some(values)) if chunk_sound(chunk, values) => {}
                _ => return false,
            }
        }
    }
    true
}

/// Whether the pages at the start of `chunk` hold exactly `values` values, each page's header
/// sound and its bytes inside the chunk.
fn chunk_sound(chunk: &[u8], values: usize) -> bool {
    let (mut at, mut seen) = (0usize, 0usize);
    while seen < values {
        let Some((header, header_len)) = chunk.get(at..).and_then(read_header) else {
            return false;
        };
        let Some(page_values) = page_values(&header, values - seen) else {
            return false;
        };
        let Ok(size) = usize::try_from(header.compressed_page_size) else {
            return false;
        };
        at = at.saturating_add(header_len).saturating_add(size);
        if at > chunk.len() || header.uncompressed_page_size < 0 {
            return false;
        }
        seen += page_values;
    }
    true
}

/// The header at the start of `bytes`, and its length.
fn read_header(mut bytes: &[u8]) -> Option<(PageHeader, usize)> {
    let len = bytes.len();
    let mut protocol = TCompactInputProtocol::new(&mut bytes, len);
    let header = PageHeader::read_from_in_protocol(&mut protocol).ok()?;
    Some((header, len - bytes.len()))
}

/// The values a data page adds (0 for a dictionary or another page), `None` if a count is
/// negative or more than `left` (a dictionary: more entries than `left`), or a data page's
/// level lengths do not fit in the page.
fn page_values(header: &PageHeader, left: usize) -> Option<usize> {
    let count = |n: i32| usize::try_from(n).ok().filter(|&n| n <= left);
    if header.type_ == PageType::DATA_PAGE {
        count(header.data_page_header.as_ref()?.num_values)
    } else if header.type_ == PageType::DATA_PAGE_V2 {
        let v2 = header.data_page_header_v2.as_ref()?;
        let levels = i64::from(v2.definition_levels_byte_length)
            + i64::from(v2.repetition_levels_byte_length);
        let fits = v2.definition_levels_byte_length >= 0
            && v2.repetition_levels_byte_length >= 0
            && levels <= i64::from(header.compressed_page_size);
        let values = count(v2.num_values)?;
        let within = |n: i32| usize::try_from(n).is_ok_and(|n| n <= values);
        (fits && within(v2.num_nulls) && within(v2.num_rows)).then_some(values)
    } else if header.type_ == PageType::DICTIONARY_PAGE {
        count(header.dictionary_page_header.as_ref()?.num_values).map(|_| 0)
    } else {
        Some(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use polars::prelude::*;
    use polars_parquet_format::thrift::protocol::TCompactOutputProtocol;
    use std::io::Cursor;

    /// A small trajectories table written by polars, with its metadata.
    fn file() -> (Vec<u8>, FileMetadata) {
        let n = 40;
        let mut df = df!(
            "run" => vec!["a"; n],
            "particle" => vec![0i64; n],
            "frame" => (0..n as i64).collect::<Vec<_>>(),
            "t_s" => (0..n).map(|i| i as f64 * 1e-3).collect::<Vec<_>>(),
            "z_m" => (0..n).map(|i| i as f64 * 1e-5).collect::<Vec<_>>(),
        )
        .unwrap();
        let mut bytes = Vec::new();
        ParquetWriter::new(&mut bytes)
            .with_compression(ParquetCompression::Uncompressed)
            .finish(&mut df)
            .unwrap();
        let metadata = ParquetReader::new(Cursor::new(&bytes))
            .get_metadata()
            .unwrap()
            .as_ref()
            .clone();
        (bytes, metadata)
    }

    const COLUMNS: [&str; 5] = ["run", "particle", "frame", "t_s", "z_m"];

    /// The first data page header of column `name`: where it starts, and the header.
    fn first_data_page(bytes: &[u8], metadata: &FileMetadata, name: &str) -> (usize, PageHeader) {
        let column = metadata.row_groups[0]
            .parquet_columns()
            .iter()
            .find(|c| c.descriptor().path_in_schema[0].as_str() == name)
            .unwrap();
        let mut at = column.byte_range().start as usize;
        loop {
            let (header, len) = read_header(&bytes[at..]).unwrap();
            if header.type_ != PageType::DICTIONARY_PAGE {
                return (at, header);
            }
            at += len + header.compressed_page_size as usize;
        }
    }

    /// The largest i32 whose compact encoding is as long as `x`'s (x ≥ 0): a size past the
    /// chunk's end in this small file, written in the place of the old one.
    fn widest(x: i32) -> i32 {
        let bytes = (64 - (2 * x as u64).leading_zeros()).div_ceil(7).max(1);
        ((1u64 << (7 * bytes)) / 2 - 1).min(i32::MAX as u64) as i32
    }

    fn v2(h: &mut PageHeader) -> &mut polars_parquet_format::DataPageHeaderV2 {
        h.data_page_header_v2.as_mut().unwrap()
    }

    /// `bytes` with the header at `at` written again as `header` (the same length).
    fn rewrite(bytes: &[u8], at: usize, header: &PageHeader) -> Vec<u8> {
        let (_, old_len) = read_header(&bytes[at..]).unwrap();
        let mut encoded = Vec::new();
        header
            .write_to_out_protocol(&mut TCompactOutputProtocol::new(&mut encoded))
            .unwrap();
        assert_eq!(
            encoded.len(),
            old_len,
            "the test needs a header of the same length: {header:?}"
        );
        let mut out = bytes.to_vec();
        out[at..at + old_len].copy_from_slice(&encoded);
        out
    }

    #[test]
    fn a_file_polars_wrote_is_sound() {
        let (bytes, metadata) = file();
        assert!(sound(&bytes, &metadata, 0..40, Some(&COLUMNS)));
    }

    #[test]
    fn a_negative_or_excess_count_or_size_is_refused() {
        let (bytes, metadata) = file();
        for name in COLUMNS {
            let (at, header) = first_data_page(&bytes, &metadata, name);
            let mut edits: Vec<Box<dyn Fn(&mut PageHeader)>> = vec![
                Box::new(|h| h.compressed_page_size = -h.compressed_page_size),
                Box::new(|h| h.uncompressed_page_size = -h.uncompressed_page_size),
                Box::new(|h| h.compressed_page_size = widest(h.compressed_page_size)),
            ];
            if header.type_ == PageType::DATA_PAGE {
                edits.push(Box::new(|h| {
                    h.data_page_header.as_mut().unwrap().num_values = -1
                }));
                edits.push(Box::new(|h| {
                    h.data_page_header.as_mut().unwrap().num_values = 63
                }));
            } else {
                edits.push(Box::new(|h| v2(h).num_values = -1));
                edits.push(Box::new(|h| v2(h).num_nulls = -1));
                edits.push(Box::new(|h| v2(h).definition_levels_byte_length = -1));
            }
            for edit in edits {
                let mut damaged = header.clone();
                edit(&mut damaged);
                let file = rewrite(&bytes, at, &damaged);
                assert!(
                    !sound(&file, &metadata, 0..40, Some(&COLUMNS)),
                    "{name}: {damaged:?}"
                );
                // a row range outside the group skips it
                assert!(sound(&file, &metadata, 40..40, Some(&COLUMNS)));
            }
        }
    }

    /// A negative count in a page whose statistics say it has nulls (so that polars decodes its
    /// validity) made polars ask for 2^61 bytes and abort the process: both readers now refuse it
    /// (checked: with `sound` always true, this test aborts).
    #[test]
    fn a_negative_count_is_an_error_not_an_abort() {
        let (bytes, metadata) = file();
        let (at, mut header) = first_data_page(&bytes, &metadata, "t_s");
        let page = header.data_page_header.as_mut().unwrap();
        page.num_values = -1;
        page.statistics.as_mut().unwrap().null_count = Some(1);
        let damaged = rewrite(&bytes, at, &header);
        let problem = super::super::table::Table::from_parquet("t.parquet", &damaged).unwrap_err();
        assert!(
            problem.to_string().contains("a page's header is damaged"),
            "{problem}"
        );
        assert!(super::super::parquet_groups::read_whole(&damaged).is_none());
    }

    #[test]
    fn a_chunk_past_the_file_is_refused() {
        let (bytes, metadata) = file();
        assert!(!sound(
            &bytes[..bytes.len() / 2],
            &metadata,
            0..40,
            Some(&COLUMNS)
        ));
    }
}
