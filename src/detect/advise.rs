//! After a run: keep the start of the input ([`Tee`]) and, when little decoded, tell the user
//! which protocol fits better ([`advise()`]).

use super::*;

/// Keeps the first [`ADVICE_BYTES`] of what a reader yields, for [`advise()`] after the run.
pub struct Tee {
    inner: Box<dyn ChunkReader>,
    kept: Arc<Mutex<Kept>>,
}

/// What a [`Tee`] kept.
#[derive(Default)]
pub struct Kept {
    pub batches: Vec<Batch>,
    /// Every byte that went through, kept or not.
    pub total: u64,
}

impl Tee {
    pub fn new(inner: Box<dyn ChunkReader>) -> (Self, Arc<Mutex<Kept>>) {
        let kept = Arc::new(Mutex::new(Kept::default()));
        (
            Tee {
                inner,
                kept: kept.clone(),
            },
            kept,
        )
    }
}

impl ChunkReader for Tee {
    fn next_batch(
        &mut self,
        tx: &std::sync::mpsc::SyncSender<Message>,
    ) -> Result<Option<Chunk>, Failure> {
        let chunk = self.inner.next_batch(tx)?;
        // The input's bytes: a byte batch, or the container bytes a capture reader hands on
        // (it keeps them when asked to, see `cli::run_capture`).
        if let Some(chunk) = &chunk
            && let Ok(mut k) = self.kept.lock()
        {
            let room = ADVICE_BYTES.saturating_sub(k.total as usize);
            let n = match chunk {
                Chunk::Bytes(b) => {
                    if room > 0 {
                        k.batches.push(b.prefix(room));
                    }
                    b.bytes.len()
                }
                Chunk::Packets(c) => {
                    if room > 0 {
                        let kept = &c.input[..room.min(c.input.len())];
                        k.batches.push(Batch::single(kept.to_vec(), None));
                    }
                    c.input.len()
                }
            };
            k.total += n as u64;
        }
        Ok(chunk)
    }
}

/// Below this share of the examined bytes in valid frames of the protocol, a run of a file or
/// stream ends with [`crate::exit::code::POOR`] (docs/usage.md, "Exit codes").
pub const POOR_SHARE: f64 = 0.5;

/// What to tell a user after a run of `protocol` on a file or stream.
#[derive(Debug, PartialEq)]
pub enum Advice {
    /// Nothing to say.
    Fine,
    /// Most of the input is not valid frames of the protocol (another fits much better, or
    /// fewer than [`POOR_SHARE`] of the bytes are in its valid frames): the message for the
    /// failure, after the rows were written (`--lenient` makes it a note).
    Poor(String),
    /// Nothing at all decoded: the message for the failure.
    NothingDecoded(String),
}

/// The message for an input that gave no wire bytes: a file of no bytes, or one whose container
/// holds none (an EdgeTX log of lines without bytes, a recording without data records).
pub fn empty_input(name: &str, kind: InputKind) -> String {
    match kind {
        InputKind::EdgeTxLog => {
            format!("empty input: {name} is an EdgeTX log whose lines carry no bytes")
        }
        InputKind::Recording => {
            format!("empty input: {name} is a busnoop recording without data records")
        }
        InputKind::Pcap | InputKind::Pcapng => {
            format!("empty input: {name} is a capture without packets")
        }
        InputKind::Trace => {
            format!("empty input: {name} is a trace whose channel carries no characters")
        }
        InputKind::Raw | InputKind::Serial => format!("empty input: {name} holds no bytes"),
    }
}

/// After a run of `protocol` over an input of `kind` that yielded `valid_frames`: is another
/// protocol a much better fit, or did almost nothing decode? `kept` is the start of the input.
pub fn advise(
    protocol: &Protocol,
    kind: InputKind,
    kept: &Kept,
    valid_frames: u64,
    source: &Path,
) -> Advice {
    let name = if source.as_os_str() == "-" {
        "standard input".to_string()
    } else {
        source.display().to_string()
    };
    if kept.total == 0 {
        return Advice::NothingDecoded(empty_input(&name, kind));
    }
    let ranked = rank(candidates(kind, None), &kept.batches, kind);
    let own = ranked
        .iter()
        .find(|r| r.protocol.command == protocol.command && !r.inverted);
    let own_share = own.map_or(0.0, |r| r.score.share());
    let better = ranked
        .iter()
        .find(|r| r.protocol.command != protocol.command || r.inverted)
        .filter(|r| {
            r.score.recognised() && r.score.share() >= 0.5 && r.score.share() >= own_share + 0.3
        });
    let suggestion = better.map(|b| {
        if b.inverted {
            format!(
                "it looks like {} with inverted bytes ({} of the bytes in {} frames once \
                 inverted): {}",
                b.protocol.name,
                percent(b.score.share()),
                b.score.frames,
                inverted_fix(b)
            )
        } else {
            format!(
                "it looks like {} ({} of the bytes in {} valid frames); try: {}",
                b.label,
                percent(b.score.share()),
                b.score.frames,
                b.command(source, None)
            )
        }
    });
    let unknown = || {
        format!(
            "`busnoop detect {}` finds no known protocol in it",
            shell_quote(source)
        )
    };
    if valid_frames == 0
        && let Some(o) = own.filter(|o| o.score.recognised())
    {
        // The protocol is right, the options are not (an S-Bus mode, a UDP port).
        return Advice::NothingDecoded(format!(
            "no {} frame in {name} with these options, but {} of its bytes are in valid {} \
             frames with the defaults; try: {}",
            protocol.name,
            percent(o.score.share()),
            o.label,
            o.command(source, None)
        ));
    }
    if valid_frames == 0
        && suggestion.is_none()
        && let Some(o) = own.filter(|o| {
            o.score.crc_errors + o.score.truncated >= MIN_FRAMES
                && o.score.bad_bytes * 2 >= o.score.total
        })
    {
        // Frames of this protocol are there, but not one passes its check.
        return Advice::NothingDecoded(format!(
            "no valid {} frame in {name}, though {} and {} look like {}: a noisy line, or \
             bytes changed on the way (capture at the wrong baud rate, a wrong inversion)",
            protocol.name,
            crate::exit::count(
                o.score.crc_errors,
                "frame with a bad check",
                "frames with a bad check"
            ),
            crate::exit::count(o.score.truncated, "truncated frame", "truncated frames"),
            protocol.name
        ));
    }
    if valid_frames == 0 {
        return Advice::NothingDecoded(format!(
            "no {} frame in {name}; {}",
            protocol.name,
            suggestion.unwrap_or_else(unknown)
        ));
    }
    if let Some(s) = suggestion {
        return Advice::Poor(format!(
            "only {} of the bytes are in valid {} frames; {s}",
            percent(own_share),
            protocol.name
        ));
    }
    if own_share < MIN_SHARE && !ranked.first().is_some_and(|r| r.score.recognised()) {
        return Advice::Poor(format!(
            "only {} of the bytes are in valid {} frames; {}",
            percent(own_share),
            protocol.name,
            unknown()
        ));
    }
    if own_share < POOR_SHARE {
        return Advice::Poor(format!(
            "only {} of the bytes are in valid {} frames (`busnoop detect {}` shows what fits)",
            percent(own_share),
            protocol.name,
            shell_quote(source)
        ));
    }
    Advice::Fine
}
