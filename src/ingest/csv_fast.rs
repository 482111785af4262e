//! Trajectory rows in the layout `groove synth` writes (`run,particle,frame,t_s,z_m`, plain
//! decimal numbers, nothing quoted, nothing blank) parsed straight into columns, two halves of a
//! piece at once, without polars: the common case read at about the speed of the bytes.
//!
//! It takes a piece only when every line matches that strict grammar; at the first thing it does
//! not know (another header, a quote, a space, an empty field, `1.`, `+1`, `inf`, a run id with
//! other characters) it gives `None` and the piece goes to polars (`columnar`), which reads what
//! this refuses. Numbers get the values Rust's correctly rounded `str::parse` gives (a plain
//! decimal by one exact division, anything else by `str::parse`), as the row-by-row path parses
//! them, so an accepted piece gives the values polars gives.

/// The one header this parser takes.
const HEADER: &[u8] = b"run,particle,frame,t_s,z_m";

/// A piece's rows as columns; run ids borrowed from the text.
#[derive(Debug, Default, PartialEq)]
pub struct Rows<'a> {
    pub ids: Vec<&'a str>,
    pub particle: Vec<i64>,
    pub frame: Vec<i64>,
    pub t_s: Vec<f64>,
    pub z_m: Vec<f64>,
}

/// The rows of `text` (the header line, then whole lines), or `None` if any line is not in the
/// strict layout: `parse_parts` joined (for the tests).
#[cfg(test)]
pub fn parse(text: &[u8]) -> Option<Rows<'_>> {
    let mut parts = parse_parts(text)?.into_iter();
    let mut all = parts.next()?;
    for b in parts {
        all.ids.extend(b.ids);
        all.particle.extend(b.particle);
        all.frame.extend(b.frame);
        all.t_s.extend(b.t_s);
        all.z_m.extend(b.z_m);
    }
    Some(all)
}

/// `parse` in consecutive parts, not joined (a copy of every column saved): the two halves of
/// a large piece, parsed on two threads, or one part for a small one.
pub fn parse_parts(text: &[u8]) -> Option<Vec<Rows<'_>>> {
    parse_body(body(text)?)
}

/// The lines after the header, if the header is the one this parser takes.
pub fn body(text: &[u8]) -> Option<&[u8]> {
    let header_end = memchr::memchr(b'\n', text)?;
    let header = &text[..header_end];
    (header.strip_suffix(b"\r").unwrap_or(header) == HEADER).then(|| &text[header_end + 1..])
}

/// The rows of whole lines (no header), in two halves parsed on two threads when there are
/// many, else in one part; `None` if any line is not in the strict layout.
pub fn parse_body(body: &[u8]) -> Option<Vec<Rows<'_>>> {
    let Some(cut) = halves(body)? else {
        return Some(vec![lines(body)?]);
    };
    let (a, b) = rayon::join(|| lines(&body[..cut]), || lines(&body[cut..]));
    Some(vec![a?, b?])
}

/// Whole lines (no header) in blocks of one run id (a line's bytes before its first comma),
/// as byte ranges in order, each from its first line's start to its last line's end (after
/// the newline, if there is one); `None` at a line with no comma. Only the ids are looked at:
/// what else a line holds is `parse_body`'s to check.
pub fn segments(body: &[u8]) -> Option<Vec<std::ops::Range<usize>>> {
    let Some(cut) = halves(body)? else {
        return segments_of(body, 0);
    };
    let (a, b) = rayon::join(
        || segments_of(&body[..cut], 0),
        || segments_of(&body[cut..], cut),
    );
    let (mut a, b) = (a?, b?);
    let mut b = b.into_iter();
    // the block open at the cut goes on after it when the id is the same
    if let (Some(last), Some(first)) = (a.last_mut(), b.next()) {
        match id_at(body, last.start) == id_at(body, first.start) {
            true => last.end = first.end,
            false => a.push(first),
        }
    }
    a.extend(b);
    Some(a)
}

/// Where whole lines of a body of a megabyte or more are cut in two halves for two threads
/// (after the first line end from the middle on); `Some(None)` for a smaller body, taken in one
/// part, and `None` for a large one with no line end in its second half.
fn halves(body: &[u8]) -> Option<Option<usize>> {
    if body.len() < 1 << 20 {
        return Some(None);
    }
    let middle = body.len() / 2;
    Some(Some(middle + memchr::memchr(b'\n', &body[middle..])? + 1))
}

/// `segments` of `part`, whose first byte is byte `offset` of the body (ranges are the body's).
fn segments_of(part: &[u8], offset: usize) -> Option<Vec<std::ops::Range<usize>>> {
    let mut out = Vec::new();
    if part.is_empty() {
        return Some(out);
    }
    let mut start = 0;
    let mut id = id_at(part, 0)?;
    for end in memchr::memchr_iter(b'\n', part) {
        let next = end + 1;
        if next >= part.len() {
            break;
        }
        let rest = &part[next..];
        if rest.starts_with(id) && rest.get(id.len()) == Some(&b',') {
            continue;
        }
        out.push(offset + start..offset + next);
        start = next;
        id = id_at(part, next)?;
    }
    if start < part.len() {
        out.push(offset + start..offset + part.len());
    }
    Some(out)
}

/// The run id of the line starting at `at`: its bytes before the first comma, which must come
/// before the line's end.
pub fn id_at(text: &[u8], at: usize) -> Option<&[u8]> {
    let line = &text[at..];
    let comma = memchr::memchr2(b',', b'\n', line)?;
    (line[comma] == b',').then(|| &line[..comma])
}

/// Every line of `body`; the last may lack its newline.
fn lines(body: &[u8]) -> Option<Rows<'_>> {
    // one check of the text, so that fields are `str` slices with no check each
    let text = std::str::from_utf8(body).ok()?;
    let guess = body.len() / 40 + 1;
    let mut rows = Rows {
        ids: Vec::with_capacity(guess),
        particle: Vec::with_capacity(guess),
        frame: Vec::with_capacity(guess),
        t_s: Vec::with_capacity(guess),
        z_m: Vec::with_capacity(guess),
    };
    // One pass along each line: the run id up to the line's first comma (checked only when it
    // differs from the line before's), then each number read as far as its grammar goes, which
    // must be exactly to the next comma (the line's end after the last). A line with a field
    // more or less, an empty one or a stray byte stops a number short of its separator.
    let mut prev: Option<&str> = None;
    let mut at = 0;
    while at < body.len() {
        let comma = at + memchr::memchr(b',', &body[at..])?;
        let id = &text[at..comma];
        if prev != Some(id) {
            prev = Some(run_id(id)?);
        }
        let (particle, end) = int_at(body, comma + 1)?;
        let (frame, end) = int_at(body, after(body, end)?)?;
        let (t_s, end) = float_at(text, after(body, end)?)?;
        let (z_m, end) = float_at(text, after(body, end)?)?;
        at = line_end(body, end)?;
        rows.ids.push(id);
        rows.particle.push(particle);
        rows.frame.push(frame);
        rows.t_s.push(t_s);
        rows.z_m.push(z_m);
    }
    Some(rows)
}

/// Where the next field starts, if a comma ends this one at `end`.
fn after(body: &[u8], end: usize) -> Option<usize> {
    (body.get(end) == Some(&b',')).then_some(end + 1)
}

/// Where the next line starts, if this one ends at `end`: a newline, a carriage return and a
/// newline, or the end of the text (after a carriage return or not).
fn line_end(body: &[u8], end: usize) -> Option<usize> {
    match (body.get(end), body.get(end + 1)) {
        (None, _) => Some(end),
        (Some(b'\n'), _) => Some(end + 1),
        (Some(b'\r'), None) => Some(end + 1),
        (Some(b'\r'), Some(b'\n')) => Some(end + 2),
        _ => None,
    }
}

/// A run id of letters, digits, `.`, `_` and `-`.
fn run_id(field: &str) -> Option<&str> {
    let ok = !field.is_empty()
        && field
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'.' | b'_' | b'-'));
    ok.then_some(field)
}

/// `-?[0-9]{1,18}` from `start`, and where it ends.
fn int_at(body: &[u8], start: usize) -> Option<(i64, usize)> {
    let negative = body.get(start) == Some(&b'-');
    let first = start + usize::from(negative);
    let digits = body.get(first..)?.iter().take_while(|b| b.is_ascii_digit());
    let (count, v) = digits.fold((0usize, 0i64), |(n, v), &d| {
        (n + 1, v.wrapping_mul(10).wrapping_add(i64::from(d - b'0')))
    });
    if count == 0 || count > 18 {
        return None;
    }
    Some((if negative { -v } else { v }, first + count))
}

/// `-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?`, the whole of `text`, valued as `str::parse` values it.
#[cfg(test)]
fn float(text: &str) -> Option<f64> {
    let (v, end) = float_at(text, 0)?;
    (end == text.len()).then_some(v)
}

/// The number `-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?` from `start` in `text`, valued as
/// `str::parse` values it, and where it ends.
fn float_at(text: &str, start: usize) -> Option<(f64, usize)> {
    let field = text.as_bytes();
    // the digits from `at` on, their count, and the integer they make (wrapping past 19 digits,
    // when it is not used)
    let digits = |at: usize, m: u64| {
        let run = field[at..].iter().take_while(|b| b.is_ascii_digit());
        run.fold((0, m), |(n, m), &d| {
            (n + 1, m.wrapping_mul(10).wrapping_add(u64::from(d - b'0')))
        })
    };
    let negative = field.get(start) == Some(&b'-');
    let mut at = start + usize::from(negative);
    if at > field.len() {
        return None;
    }
    let (whole, mut m) = digits(at, 0);
    if whole == 0 {
        return None;
    }
    at += whole;
    let mut frac = 0;
    if field.get(at) == Some(&b'.') {
        (frac, m) = digits(at + 1, m);
        if frac == 0 {
            return None;
        }
        at += 1 + frac;
    }
    let exponent = matches!(field.get(at), Some(b'e' | b'E'));
    if exponent {
        at += 1;
        if matches!(field.get(at), Some(b'-' | b'+')) {
            at += 1;
        }
        let (exp, _) = digits(at, 0);
        if exp == 0 {
            return None;
        }
        at += exp;
    }
    // a plain decimal of at most 19 digits whose digits make an integer below 2^53, over a
    // power of ten up to 10^22: both exact in f64, so one correctly rounded division gives what
    // `str::parse` gives, at a fraction of its cost; anything else goes to `str::parse`
    if !exponent && whole + frac <= 19 && frac < POW10.len() && m < 1 << 53 {
        let v = m as f64 / POW10[frac];
        return Some((if negative { -v } else { v }, at));
    }
    Some((text[start..at].parse().ok()?, at))
}

/// 10^0 ..= 10^22, each exact in f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_are_the_blocks_of_one_run_id_on_either_side_of_the_cut() {
        let body = b"a,1\r\na,2\nab,3\nb,4\na,5";
        let got: Vec<&[u8]> = segments(body)
            .unwrap()
            .into_iter()
            .map(|r| &body[r])
            .collect();
        let want: [&[u8]; 4] = [b"a,1\r\na,2\n", b"ab,3\n", b"b,4\n", b"a,5"];
        assert_eq!(got, want);
        assert_eq!(segments(b""), Some(Vec::new()));
        // a line without a comma, or an empty line
        assert_eq!(segments(b"a,1\nb\nc,2\n"), None);
        assert_eq!(segments(b"a,1\n\nc,2\n"), None);
        // a body of 2 MB cut in two halves: the same blocks as in one pass, whether a block
        // goes on across the cut or ends there
        for width in [3000usize, 7919] {
            let mut big = Vec::new();
            let mut k = 0usize;
            while big.len() < 2 << 20 {
                big.extend(format!("r{},{k}\n", k / width).as_bytes());
                k += 1;
            }
            let one_pass = segments_of(&big, 0).unwrap();
            assert_eq!(segments(&big).unwrap(), one_pass);
            assert_eq!(one_pass.len(), k.div_ceil(width));
        }
    }

    #[test]
    fn the_strict_layout_is_parsed_and_anything_else_is_left_to_polars() {
        let text = b"run,particle,frame,t_s,z_m\r\ns-1,0,0,0.0000000,0.001099000\r\ns-1,1,-2,1e-4,-2.5E+3\nc_2,3,4,5,6";
        let rows = parse(text).unwrap();
        assert_eq!(rows.ids, ["s-1", "s-1", "c_2"]);
        assert_eq!(rows.particle, [0, 1, 3]);
        assert_eq!(rows.frame, [0, -2, 4]);
        assert_eq!(rows.t_s, [0.0, 1e-4, 5.0]);
        assert_eq!(rows.z_m, [0.001099, -2500.0, 6.0]);
        assert_eq!(
            parse(b"run,particle,frame,t_s,z_m\n").unwrap(),
            Rows::default()
        );
        // a carriage return at the very end, with no newline after it
        let rows = parse(b"run,particle,frame,t_s,z_m\na,0,0,1.5,-2\r").unwrap();
        assert_eq!((rows.t_s, rows.z_m), (vec![1.5], vec![-2.0]));
        let head = "run,particle,frame,t_s,z_m\n";
        for bad in [
            "run,frame,particle,t_s,z_m\na,0,0,0,0\n".to_string(),
            format!("{head}a,0,0,0,0\n\na,0,1,0,0\n"),
            format!("{head}\"a\",0,0,0,0\n"),
            format!("{head}a ,0,0,0,0\n"),
            format!("{head}a,0,0,0\n"),
            format!("{head}a,0,0,0,0,\n"),
            format!("{head}a,,0,0,0\n"),
            format!("{head}a,0.0,0,0,0\n"),
            format!("{head}a,0,0,1.,0\n"),
            format!("{head}a,0,0,.5,0\n"),
            format!("{head}a,0,0,+1,0\n"),
            format!("{head}a,0,0,inf,0\n"),
            format!("{head}a,0,0,NaN,0\n"),
            format!("{head}a,0,0,1e,0\n"),
            format!("{head}a,0,0,0, 1\n"),
            format!("{head}a,0,0,0,1\u{a0}\n"),
            format!("{head}a,1234567890123456789,0,0,0\n"),
            // an id left empty after a good line (ids are checked only when they change)
            format!("{head}a,0,0,0,0\n,0,0,0,0\n"),
            format!("{head}\na,0,0,0,0\n"),
            format!("{head}a,0\r,0,0,0\n"),
            format!("{head}a,0,0,0,0\r\r\n"),
            format!("{head}a,0,0,0,0\ra,0,1,0,0\n"),
            format!("{head}a,0,0,0,-\n"),
            format!("{head}a,0,0,0,1e+\n"),
            format!("{head}a,0,0,0,0\nb\n"),
        ] {
            assert_eq!(parse(bad.as_bytes()), None, "{bad:?}");
        }
    }

    #[test]
    fn plain_decimals_are_valued_bit_for_bit_as_str_parse_values_them() {
        let mut state = 5u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            state >> 11
        };
        let mut fields: Vec<String> = [
            "0",
            "-0",
            "0.0",
            "-0.0",
            "1",
            "9007199254740991",
            "9007199254740992",
            "9007199254740993",
            "1234567890123456789",
            "0.1",
            "0.30000000000000004",
            "123456789.0123456789",
            "0.0000000000000000000001",
            "-0.001099000",
            "5.5e-3",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for _ in 0..200_000 {
            let (w, f) = (next() % 12, next() % 24);
            let whole = (next() % 10u64.pow(w as u32)).to_string();
            let digits: String = (0..f)
                .map(|_| char::from(b'0' + (next() % 10) as u8))
                .collect();
            let sign = if next() % 2 == 0 { "-" } else { "" };
            fields.push(match f {
                0 => format!("{sign}{whole}"),
                _ => format!("{sign}{whole}.{digits}"),
            });
        }
        for f in &fields {
            let want: f64 = f.parse().unwrap();
            assert_eq!(float(f).unwrap().to_bits(), want.to_bits(), "{f}");
        }
    }

    #[test]
    fn the_numbers_are_those_of_str_parse_and_halves_join_in_order() {
        let mut text = String::from("run,particle,frame,t_s,z_m\n");
        for i in 0..40_000u64 {
            let t = (i as f64) * 1e-4 + 1.0 / 3.0;
            let z = ((i * 7919) % 1000) as f64 * 1.1e-6 - 3e-4;
            let line = format!("r{},{},{},{t:.9},{z:e}\n", i / 600, i % 3, i);
            text.push_str(&line);
        }
        assert!(text.len() > 1 << 20, "two halves");
        assert_eq!(parse_parts(text.as_bytes()).unwrap().len(), 2);
        let rows = parse(text.as_bytes()).unwrap();
        assert_eq!(rows.frame, (0..40_000).collect::<Vec<i64>>());
        for (k, line) in text.lines().skip(1).enumerate() {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(rows.ids[k], f[0]);
            assert_eq!(
                rows.t_s[k].to_bits(),
                f[3].parse::<f64>().unwrap().to_bits()
            );
            assert_eq!(
                rows.z_m[k].to_bits(),
                f[4].parse::<f64>().unwrap().to_bits()
            );
        }
        assert_eq!(rows.t_s.len(), 40_000);
    }
}
