//! Where formatted rows go: standard output or a file, written in whole rows only.
//!
//! Rows are appended to an in-memory buffer and written out in whole rows, so a reader of the
//! output never sees half a row. When a write to a file fails (a full disk), the file is cut
//! back to the end of the last row that was written completely.

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::files::create_file;
use crate::row::OutputError;
use crate::row::line::{self, W};

/// Flush the buffer once it holds this much.
pub(super) const HIGH_WATER: usize = 64 * 1024;

enum Dest {
    Stdout(io::Stdout),
    File {
        file: File,
        path: PathBuf,
        /// A regular file (synced at the end, cut back after a failed write).
        regular: bool,
    },
    #[cfg(test)]
    Memory(Vec<u8>),
}

/// A buffered destination that only ever writes complete rows (or records of a binary file:
/// recordings and exports, [`Output::record`]); a failed write cuts a regular file back to the
/// last complete one.
pub struct Output {
    dest: Dest,
    /// `buf[..len]` are the rows not written out yet; the rest is room for the next line
    /// (zeroed once, so that a line is written into it without a check per byte).
    buf: Vec<u8>,
    len: usize,
    /// Bytes known to be in the file (whole rows).
    committed: u64,
    /// Last write error; once set, nothing more is written.
    failed: bool,
}

impl Output {
    pub fn stdout() -> Self {
        Self::new(Dest::Stdout(io::stdout()))
    }

    /// Creates (truncates) `path`. It may also be a special file (`/dev/null`, `/dev/stdout`,
    /// a FIFO): those are written to but never synced.
    pub fn create(path: &Path) -> io::Result<Self> {
        Self::file(create_file(path)?, path)
    }

    /// Writes into `file`, created from `path` with [`create_file`].
    pub(crate) fn file(file: File, path: &Path) -> io::Result<Self> {
        let regular = file.metadata()?.is_file();
        Ok(Self::new(Dest::File {
            file,
            path: path.to_owned(),
            regular,
        }))
    }

    /// Keeps everything in memory (tests).
    #[cfg(test)]
    pub fn memory() -> Self {
        Self::new(Dest::Memory(Vec::new()))
    }

    fn new(dest: Dest) -> Self {
        Output {
            dest,
            buf: vec![0; HIGH_WATER * 2],
            len: 0,
            committed: 0,
            failed: false,
        }
    }

    /// Appends whole rows with `append`: for text written seldom (headers, the wide table).
    /// Call [`Output::row_done`] after each row.
    pub fn append(&mut self, append: impl FnOnce(&mut Vec<u8>)) {
        self.buf.truncate(self.len);
        append(&mut self.buf);
        self.len = self.buf.len();
        self.buf.resize(self.len + line::ROOM, 0);
    }

    /// Appends one row, written with `write` straight into the buffer's room (see
    /// [`line::write_line`]). Call [`Output::row_done`] after it.
    #[inline(always)]
    pub(super) fn line(&mut self, write: impl FnMut(&mut W<'_>)) {
        self.len += line::write_line(&mut self.buf, self.len, write);
    }

    /// The buffer and the length of the rows in it, for rows written straight into its room
    /// ([`crate::row::Direct`]); `None` once enough is buffered to be written out.
    #[inline]
    pub(super) fn room(&mut self) -> Option<(&mut Vec<u8>, &mut usize)> {
        if self.len >= HIGH_WATER {
            return None;
        }
        Some((&mut self.buf, &mut self.len))
    }

    /// Appends one whole record of a binary file (a recording's packet, an export's block, or
    /// a header with its first packet) and writes out when enough has gathered: like a row, a
    /// record is never cut by a failed write (a full disk), which Wireshark would report as
    /// "cut short in the middle of a packet".
    pub(crate) fn record(&mut self, bytes: &[u8]) -> Result<(), OutputError> {
        let end = self.len + bytes.len();
        if self.buf.len() < end + line::ROOM {
            self.buf.resize(end + line::ROOM, 0);
        }
        self.buf[self.len..end].copy_from_slice(bytes);
        self.len = end;
        self.row_done()
    }

    /// A complete row is in the buffer: write out when enough has gathered.
    #[inline]
    pub fn row_done(&mut self) -> Result<(), OutputError> {
        if self.len >= HIGH_WATER {
            self.flush()
        } else {
            Ok(())
        }
    }

    /// Writes every buffered row.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        let rows = &self.buf[..self.len];
        if self.failed || rows.is_empty() {
            self.len = 0;
            return Ok(());
        }
        let result = match &mut self.dest {
            Dest::Stdout(s) => {
                let mut lock = s.lock();
                lock.write_all(rows).and_then(|_| lock.flush())
            }
            Dest::File { file, .. } => file.write_all(rows),
            #[cfg(test)]
            Dest::Memory(v) => {
                v.extend_from_slice(rows);
                Ok(())
            }
        };
        let written = rows.len();
        self.len = 0;
        match result {
            Ok(()) => {
                self.committed += written as u64;
                Ok(())
            }
            Err(error) => {
                self.failed = true;
                let path = match &mut self.dest {
                    Dest::File {
                        file,
                        path,
                        regular,
                    } => {
                        // Cut a partly written row off again; ignore errors, the write error
                        // is what the user needs to see.
                        if *regular {
                            let _ = file.set_len(self.committed);
                            let _ = file.seek(SeekFrom::Start(self.committed));
                        }
                        Some(path.clone())
                    }
                    _ => None,
                };
                Err(OutputError { path, error })
            }
        }
    }

    /// Flushes, and syncs a regular file to disk.
    pub fn close(&mut self) -> Result<(), OutputError> {
        self.flush()?;
        if let Dest::File {
            file,
            path,
            regular: true,
        } = &mut self.dest
            && !self.failed
        {
            file.sync_data().map_err(|error| OutputError {
                path: Some(path.clone()),
                error,
            })?;
        }
        Ok(())
    }

    /// The bytes written so far (memory outputs only).
    #[cfg(test)]
    pub fn memory_contents(&self) -> &[u8] {
        match &self.dest {
            Dest::Memory(v) => v,
            _ => &[],
        }
    }
}
