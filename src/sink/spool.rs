//! Where the wide table of a file or pipe waits for its header ([`super::wide`]): the header is
//! complete only at the end of the input, so every line is kept until then. Decoding is
//! streaming and memory must stay flat whatever the input's size, so the lines are kept in
//! memory only up to a small, fixed amount ([`MEMORY`]); beyond it they go to an unnamed
//! temporary file in [`std::env::temp_dir`] (`$TMPDIR`), which is read back once, in order, at
//! the end.
//!
//! A line is kept as a record of what changed since the line before (the wide table writes it,
//! [`super::wide`]), so that the spool grows with the input, never with lines × columns. Each
//! record is its length in bytes (`u32`, little-endian) and its bytes. Nothing else is kept per
//! record, so the bookkeeping does not grow with the capture either.

use std::fs::File;
use std::io::{self, BufReader, Cursor, Read, Seek, SeekFrom, Write};

/// Bytes of records kept in memory before they are written to the temporary file.
pub const MEMORY: usize = 1 << 20;

/// Bytes of a record before its bytes: their length.
const HEAD: usize = 4;

/// The records of the wide table's lines, in memory and then in a temporary file.
pub struct Spool {
    /// Records not yet written to the file; at most about `limit` bytes.
    mem: Vec<u8>,
    limit: usize,
    /// The temporary file, once the records outgrew memory.
    file: Option<File>,
    /// Records pushed and not yet read back: the reader expects exactly this many, so a file
    /// cut short is an error, never a short table.
    count: u64,
    /// Bytes of records pushed in all (tests check that the spool grows with the input).
    total: u64,
    /// The records being read back (after [`Spool::rewind`]).
    reader: Option<Box<dyn Read>>,
}

impl Spool {
    /// A spool keeping up to `limit` bytes of records in memory.
    pub fn new(limit: usize) -> Self {
        Spool {
            mem: Vec::new(),
            limit,
            file: None,
            count: 0,
            total: 0,
            reader: None,
        }
    }

    /// Adds a record.
    pub fn push(&mut self, record: &[u8]) -> io::Result<()> {
        let len = u32::try_from(record.len())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "a line is over 4 GiB"))?;
        self.mem.extend_from_slice(&len.to_le_bytes());
        self.mem.extend_from_slice(record);
        self.count += 1;
        self.total += (HEAD + record.len()) as u64;
        if self.mem.len() >= self.limit {
            let file = match &mut self.file {
                Some(f) => f,
                None => self.file.insert(temp_file()?),
            };
            file.write_all(&self.mem)?;
            // Keeps the capacity: the next records fill the same memory.
            self.mem.clear();
        }
        Ok(())
    }

    /// Bytes of records held in memory (tests check the bound).
    #[cfg(test)]
    pub fn in_memory(&self) -> usize {
        self.mem.len()
    }

    /// Bytes of records pushed in all, in memory and in the file (tests).
    #[cfg(test)]
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Whether records went to the temporary file (tests).
    #[cfg(test)]
    pub fn spilled(&self) -> bool {
        self.file.is_some()
    }

    /// Ends the writing: the records are read back from the first, with [`Spool::next`].
    pub fn rewind(&mut self) -> io::Result<()> {
        let mem = std::mem::take(&mut self.mem);
        self.reader = Some(match self.file.take() {
            Some(mut file) => {
                file.write_all(&mem)?;
                drop(mem);
                file.seek(SeekFrom::Start(0))?;
                Box::new(BufReader::with_capacity(64 * 1024, file))
            }
            None => Box::new(Cursor::new(mem)),
        });
        Ok(())
    }

    /// The next record read back into `record` (replacing its content); `false` after the
    /// last.
    pub fn next(&mut self, record: &mut Vec<u8>) -> io::Result<bool> {
        let Some(reader) = &mut self.reader else {
            return Ok(false);
        };
        if self.count == 0 {
            self.reader = None;
            return Ok(false);
        }
        let short = |e: io::Error| match e.kind() {
            io::ErrorKind::UnexpectedEof => io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the temporary file is shorter than what was written to it",
            ),
            _ => e,
        };
        let mut head = [0; HEAD];
        reader.read_exact(&mut head).map_err(short)?;
        record.clear();
        record.resize(u32::from_le_bytes(head) as usize, 0);
        reader.read_exact(record).map_err(short)?;
        self.count -= 1;
        Ok(true)
    }

    /// Whether records remain to be read back.
    pub fn has_more(&self) -> bool {
        self.count > 0
    }
}

/// An unnamed temporary file in [`std::env::temp_dir`]: nothing is left behind when busnoop
/// ends, even by a crash or a kill. Linux: `O_TMPFILE` (the file never has a name); elsewhere,
/// or where the file system lacks it, a new file with a unique name, removed at once (it lives on
/// while open).
fn temp_file() -> io::Result<File> {
    let dir = std::env::temp_dir();
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        if let Ok(f) = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .mode(0o600)
            .custom_flags(libc::O_TMPFILE)
            .open(&dir)
        {
            return Ok(f);
        }
    }
    let unique = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let path = dir.join(format!(".busnoop-wide-{}-{unique}.tmp", std::process::id()));
    let mut options = std::fs::OpenOptions::new();
    options.read(true).write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        options.mode(0o600);
    }
    let file = options.open(&path)?;
    // On systems that cannot remove an open file, it stays until busnoop ends; the error is
    // no reason to fail the table.
    let _ = std::fs::remove_file(&path);
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_come_back_in_order_from_memory_and_from_the_file() {
        for limit in [MEMORY, 64] {
            let mut s = Spool::new(limit);
            for i in 0..1000usize {
                s.push(format!("line {i}").as_bytes()).unwrap();
                assert!(s.in_memory() < limit + 64, "memory stays bounded");
            }
            assert_eq!(s.spilled(), limit == 64);
            s.rewind().unwrap();
            let mut line = Vec::new();
            for i in 0..1000usize {
                assert!(s.next(&mut line).unwrap());
                assert_eq!(line, format!("line {i}").as_bytes());
            }
            assert!(!s.next(&mut line).unwrap());
            assert!(!s.has_more());
        }
    }
}
