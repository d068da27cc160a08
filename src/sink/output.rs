//! Where formatted rows go: standard output or a file, written in whole rows only.
//!
//! Rows are appended to an in-memory buffer and written out in whole rows, so a reader of the
//! output never sees half a row. When a write to a file fails (a full disk), the file is cut
//! back to the end of the last row that was written completely.

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::row::OutputError;

/// Flush the buffer once it holds this much.
const HIGH_WATER: usize = 64 * 1024;

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

/// A buffered destination that only ever writes complete rows.
pub struct Output {
    dest: Dest,
    buf: Vec<u8>,
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
        let file = File::create(path)?;
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
            buf: Vec::with_capacity(HIGH_WATER * 2),
            committed: 0,
            failed: false,
        }
    }

    /// The buffer to append whole rows to. Call [`Output::row_done`] after each row.
    pub fn buf(&mut self) -> &mut Vec<u8> {
        &mut self.buf
    }

    /// A complete row is in the buffer: write out when enough has gathered.
    #[inline]
    pub fn row_done(&mut self) -> Result<(), OutputError> {
        if self.buf.len() >= HIGH_WATER {
            self.flush()
        } else {
            Ok(())
        }
    }

    /// Writes every buffered row.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        if self.failed {
            self.buf.clear();
            return Ok(());
        }
        if self.buf.is_empty() {
            return Ok(());
        }
        let result = match &mut self.dest {
            Dest::Stdout(s) => {
                let mut lock = s.lock();
                lock.write_all(&self.buf).and_then(|_| lock.flush())
            }
            Dest::File { file, .. } => file.write_all(&self.buf),
            #[cfg(test)]
            Dest::Memory(v) => {
                v.extend_from_slice(&self.buf);
                Ok(())
            }
        };
        match result {
            Ok(()) => {
                self.committed += self.buf.len() as u64;
                self.buf.clear();
                Ok(())
            }
            Err(error) => {
                self.failed = true;
                self.buf.clear();
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
