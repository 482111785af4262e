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
pub fn for_each_piece(
    read: &mut (dyn Read + Send),
    chunk_bytes: usize,
    piece: &mut dyn FnMut(&[u8]) -> Result<(), Stop>,
) -> Result<usize, Stop> {
    const BLOCK: u64 = 1 << 20;
    std::thread::scope(|scope| {
        let (blocks, received) = std::sync::mpsc::sync_channel(8);
        scope.spawn(move || loop {
            let mut block = Vec::with_capacity(BLOCK as usize);
            match read.take(BLOCK).read_to_end(&mut block) {
                Ok(0) => return,
                Ok(_) => {
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
            block: Vec::new(),
            at: 0,
        };
        pieces(&mut ahead, chunk_bytes, piece)
    })
}

/// The blocks the reading thread sent, as a reader.
struct Ahead {
    received: std::sync::mpsc::Receiver<std::io::Result<Vec<u8>>>,
    block: Vec<u8>,
    at: usize,
}

impl Read for Ahead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.at == self.block.len() {
            match self.received.recv() {
                Ok(block) => (self.block, self.at) = (block?, 0),
                Err(_) => return Ok(0), // the reading thread is done: the end
            }
        }
        let n = buf.len().min(self.block.len() - self.at);
        buf[..n].copy_from_slice(&self.block[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

/// `for_each_piece` on the reader itself.
fn pieces(
    read: &mut dyn Read,
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
        eof = fill(read, &mut buf, 64 << 10)? == 0;
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
            eof = fill(read, &mut buf, more)? == 0;
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

/// Appends up to `n` bytes from `read` to `buf`; how many (0 at the end).
fn fill(read: &mut dyn Read, buf: &mut Vec<u8>, n: usize) -> Result<usize, Stop> {
    read.take(n as u64).read_to_end(buf).map_err(Stop::Read)
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
