//! A CSV read from any reader in pieces of whole lines, each handed on behind the header line, so
//! that a file larger than memory is parsed a piece at a time.

use std::io::Read;

/// Why reading in pieces stopped early.
#[derive(Debug)]
pub enum Stop {
    /// The data is not for the fast path (the caller reads the dataset whole, which says why in
    /// detail): the reason, for the progress line.
    Reason(&'static str),
    /// The file could not be read, or changed while it was read: an error to report.
    Read(std::io::Error),
}

impl From<&'static str> for Stop {
    fn from(why: &'static str) -> Stop {
        Stop::Reason(why)
    }
}

/// Hands `piece` the header line followed by whole lines, at most `chunk_bytes` of them (more
/// only where one line is longer), until the reader is empty; a byte-order mark before the header
/// is dropped. The last line need not end in a newline. Gives the number of pieces (none for a
/// header without data); a file without a line end is refused.
///
/// The reader is read on a thread of its own a megabyte at a time, a few megabytes ahead of the
/// pieces (so that reading, and the hashing `InputFile`'s reader does, overlap the parsing).
/// The blocks go back to that thread once their bytes are in a piece and are read into again:
/// a `read_to_end` into fresh capacity zeroes it first (a reader behind `dyn Read` cannot take
/// uninitialized memory), which cost as much as the read itself.
pub fn for_each_piece(
    read: &mut (dyn Read + Send),
    chunk_bytes: usize,
    piece: &mut dyn FnMut(&[u8]) -> Result<(), Stop>,
) -> Result<usize, Stop> {
    const BLOCK: usize = 1 << 20;
    std::thread::scope(|scope| {
        let (blocks, received) = std::sync::mpsc::sync_channel(8);
        let (spare, spares) = std::sync::mpsc::channel::<Vec<u8>>();
        scope.spawn(move || loop {
            let mut block = spares.try_recv().unwrap_or_default();
            block.resize(BLOCK, 0);
            match read_full(read, &mut block) {
                Ok(0) => return,
                Ok(n) => {
                    block.truncate(n);
                    if blocks.send(Ok(block)).is_err() {
                        return; // the pieces stopped early
                    }
                }
                Err(e) => {
                    let _ = blocks.send(Err(e));
                    return;
                }
            }
        });
        let mut ahead = Ahead {
            received,
            spare,
            block: Vec::new(),
            at: 0,
        };
        pieces(&mut ahead, chunk_bytes, piece)
    })
}

/// Reads until `buf` is full or the reader is at its end; how many bytes.
fn read_full(read: &mut dyn Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match read.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// The blocks the reading thread sent, and the way back for those used up.
struct Ahead {
    received: std::sync::mpsc::Receiver<std::io::Result<Vec<u8>>>,
    spare: std::sync::mpsc::Sender<Vec<u8>>,
    block: Vec<u8>,
    at: usize,
}

impl Ahead {
    /// Appends up to `n` bytes to `buf`; how many (0 at the end).
    fn append(&mut self, buf: &mut Vec<u8>, n: usize) -> Result<usize, Stop> {
        let mut added = 0;
        while added < n {
            if self.at == self.block.len() {
                let next = match self.received.recv() {
                    Ok(block) => block.map_err(Stop::Read)?,
                    Err(_) => break, // the reading thread is done: the end
                };
                let used = std::mem::replace(&mut self.block, next);
                // the reading thread is gone only when the pieces stopped early
                let _ = self.spare.send(used);
                self.at = 0;
            }
            let k = (n - added).min(self.block.len() - self.at);
            buf.extend_from_slice(&self.block[self.at..self.at + k]);
            self.at += k;
            added += k;
        }
        Ok(added)
    }
}

/// `for_each_piece` on the blocks read ahead.
fn pieces(
    read: &mut Ahead,
    chunk_bytes: usize,
    piece: &mut dyn FnMut(&[u8]) -> Result<(), Stop>,
) -> Result<usize, Stop> {
    let chunk = chunk_bytes.max(1);
    let mut buf = Vec::with_capacity(chunk + (64 << 10));
    let mut searched = 0;
    let mut eof = false;
    let header_end = loop {
        if let Some(k) = buf[searched..].iter().position(|&b| b == b'\n') {
            break searched + k + 1;
        }
        searched = buf.len();
        if eof {
            return Err(Stop::Reason("the trajectories file has no line end"));
        }
        eof = read.append(&mut buf, 64 << 10)? == 0;
    };
    let header_end = match buf.strip_prefix(b"\xEF\xBB\xBF") {
        Some(_) => {
            buf.drain(..3);
            header_end - 3
        }
        None => header_end,
    };
    let mut pieces = 0;
    let mut want = chunk;
    loop {
        while !eof && buf.len() - header_end < want {
            let more = want - (buf.len() - header_end);
            eof = read.append(&mut buf, more)? == 0;
        }
        if buf.len() == header_end {
            return Ok(pieces);
        }
        let body = &buf[header_end..];
        let newline = |b: &u8| *b == b'\n';
        let cut = if eof && body.len() <= chunk {
            buf.len()
        } else {
            // the last line end within a piece, else the end of a line longer than a piece
            match body[..chunk.min(body.len())].iter().rposition(newline) {
                Some(k) => header_end + k + 1,
                None => match body.iter().position(newline) {
                    Some(k) => header_end + k + 1,
                    None if eof => buf.len(),
                    None => {
                        want += chunk;
                        continue;
                    }
                },
            }
        };
        piece(&buf[..cut])?;
        pieces += 1;
        buf.drain(header_end..cut);
        want = chunk;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pieces(text: &[u8], chunk: usize) -> Result<Vec<String>, Stop> {
        let mut out = Vec::new();
        for_each_piece(&mut &text[..], chunk, &mut |p| {
            out.push(String::from_utf8(p.to_vec()).unwrap());
            Ok(())
        })?;
        Ok(out)
    }

    #[test]
    fn pieces_are_whole_lines_behind_the_header_and_hold_every_line_once() {
        let text = "\u{feff}h1,h2\n1,a\n22,bb\n333,ccc\n4,d";
        for chunk in 1..40 {
            let got = pieces(text.as_bytes(), chunk).unwrap();
            let mut lines = String::new();
            for p in &got {
                let body = p
                    .strip_prefix("h1,h2\n")
                    .expect("each piece starts with the header");
                assert!(body.len() <= chunk || !body[..body.len() - 1].contains('\n'));
                assert!(!body.is_empty());
                lines.push_str(body);
            }
            assert_eq!(lines, "1,a\n22,bb\n333,ccc\n4,d", "chunk {chunk}");
        }
        assert_eq!(pieces(b"h1,h2\n", 8).unwrap().len(), 0);
        assert!(matches!(pieces(b"h1,h2", 8), Err(Stop::Reason(_))));
    }
}
