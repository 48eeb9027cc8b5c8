//! [`RecordingPlayer`]: publishes a recording's cuts as a live scene, with their recorded
//! timing, through the same transport a [`crate::SceneWriter`] uses.

use std::collections::HashMap;
use std::time::{Duration, Instant};
use ygg_store::recording::{Recording, RecordingError};
use ygg_transport::{PublishError, PublisherBuilder, SegmentPublisher, WriterWaitError};

/// Why a replay stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// A recorded cut could not be read or failed validation (it is not published).
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The transport refused a segment or the manifest.
    #[error(transparent)]
    Publish(#[from] PublishError),
    /// SIGINT or SIGTERM arrived while waiting for the next cut's time.
    #[error(transparent)]
    Interrupted(#[from] WriterWaitError),
}

/// How to play a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlayOptions {
    /// Playback speed: 2.0 plays twice as fast as recorded (default 1.0).
    pub speed: f64,
    /// The first cut to play (index into [`Recording::cuts`]).
    pub from_cut: usize,
    /// Start again at `from_cut` after the last cut, forever.
    pub looped: bool,
}

impl Default for PlayOptions {
    fn default() -> Self {
        PlayOptions {
            speed: 1.0,
            from_cut: 0,
            looped: false,
        }
    }
}

/// Publishes recorded cuts as a live scene: each cut's changed segments (the recorded,
/// validated bytes, copied once into shared memory), then its manifest. Readers cannot
/// tell it from a live writer: the wire format, catch-up of late readers and generations
/// that only grow are the transport's.
pub struct RecordingPlayer {
    publisher: SegmentPublisher,
    recording: Recording,
    /// Per segment id: the recorded `(session, generation)` published, and the
    /// generation it was published under.
    published: HashMap<u64, ((u64, u64), u64)>,
    /// The last manifest generation published, and what is added to recorded generations
    /// so that they only grow (across loops and recorded writer restarts).
    generation: u64,
    generation_offset: u64,
    /// Per cut published: how late it went out against its schedule (for reports).
    lateness: Vec<Duration>,
}

impl RecordingPlayer {
    /// A player of `recording` as scene `scene`; `publisher` configures the transport
    /// (its scene name is the one used). The segment bound is raised to what the
    /// recording's largest cut needs.
    ///
    /// # Errors
    /// As [`PublisherBuilder::create`] (a live writer already publishes the scene, ...).
    pub fn new(
        recording: Recording,
        publisher: PublisherBuilder,
    ) -> Result<Self, ygg_transport::WriterCreateError> {
        let most = recording
            .cuts()
            .iter()
            .map(|c| c.segments as usize)
            .max()
            .unwrap_or(1);
        let publisher = publisher.max_segments(most * 2).create()?;
        Ok(RecordingPlayer {
            publisher,
            recording,
            published: HashMap::new(),
            generation: 0,
            generation_offset: 0,
            lateness: Vec::new(),
        })
    }

    /// The transport publisher (scene name, session).
    pub fn publisher(&self) -> &SegmentPublisher {
        &self.publisher
    }

    /// The recording played.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }

    /// The generation readers see for the last cut published (the recorded one when
    /// generations only grew in the recording).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// How late each cut played by [`RecordingPlayer::play`] went out against its
    /// schedule (the recorded offset from the first cut, divided by the speed).
    pub fn lateness(&self) -> &[Duration] {
        &self.lateness
    }

    /// Publishes cut `cut` now: validates it (once per recorded segment), sends the
    /// segments readers do not hold, then the manifest.
    ///
    /// # Errors
    /// [`ReplayError::Recording`] for a cut that does not validate (nothing is sent),
    /// [`ReplayError::Publish`] from the transport.
    pub fn publish_cut(&mut self, cut: usize) -> Result<(), ReplayError> {
        // A cut that fails validation is never sent.
        drop(self.recording.scene(cut)?);
        self.send_cut(cut)
    }

    /// Sends cut `cut`, which [`Recording::scene`] validated before.
    fn send_cut(&mut self, cut: usize) -> Result<(), ReplayError> {
        let raw = self.recording.raw_cut(cut)?;
        let session = raw.summary.session;
        self.publisher.start_cut();
        let mut entries = Vec::with_capacity(raw.segments.len());
        for s in &raw.segments {
            let key = (session, s.generation);
            let generation = match self.published.get(&s.id) {
                Some((k, g)) if *k == key => *g,
                last => {
                    // Segment generations only grow per id, whatever the recording did.
                    let g = last.map_or(s.generation, |(_, g)| s.generation.max(g + 1));
                    self.publisher
                        .publish_layer(s.id, g, s.bytes.len(), |buf| {
                            buf.copy_from_slice(s.bytes)
                        })?;
                    self.published.insert(s.id, (key, g));
                    g
                }
            };
            entries.push(ygg_transport::protocol::ManifestEntry {
                layer_id: s.id,
                generation,
            });
        }
        let gone: Vec<u64> = self
            .published
            .keys()
            .filter(|id| entries.binary_search_by_key(*id, |e| e.layer_id).is_err())
            .copied()
            .collect();
        let mut generation = raw.summary.generation + self.generation_offset;
        if generation <= self.generation {
            self.generation_offset += self.generation + 1 - generation;
            generation = self.generation + 1;
        }
        self.publisher
            .publish_manifest(generation, &entries, raw.manifest.len(), |buf| {
                buf.copy_from_slice(raw.manifest)
            })?;
        self.generation = generation;
        for id in gone {
            self.publisher.retire_layer(id);
            self.published.remove(&id);
        }
        Ok(())
    }

    /// Plays the recording from `options.from_cut` with its recorded timing (the writer's
    /// publish times, divided by `options.speed`), once or in a loop; `on_cut` is called
    /// after each cut went out, and stops the play by returning false. Returns the number
    /// of cuts published.
    ///
    /// # Errors
    /// As [`RecordingPlayer::publish_cut`], and [`ReplayError::Interrupted`] on SIGINT or
    /// SIGTERM (the player should then be dropped, which removes its shared memory).
    pub fn play(
        &mut self,
        options: PlayOptions,
        mut on_cut: impl FnMut(usize) -> bool,
    ) -> Result<u64, ReplayError> {
        let cuts = self.recording.cuts().to_vec();
        let first = options.from_cut.min(cuts.len().saturating_sub(1));
        let speed = if options.speed.is_finite() && options.speed > 0.0 {
            options.speed
        } else {
            1.0
        };
        let mut published = 0;
        loop {
            let start = Instant::now();
            let origin = cuts[first].writer_unix_ns;
            for (i, cut) in cuts.iter().enumerate().skip(first) {
                let offset = cut.writer_unix_ns.saturating_sub(origin) as f64 / speed;
                let due = start + Duration::from_nanos(offset as u64);
                // Validated (once per segment) and joined before its time, so that only
                // the copy into shared memory is left when it is due.
                drop(self.recording.scene(i)?);
                wait_until(&self.publisher, due)?;
                let late = Instant::now().saturating_duration_since(due);
                self.send_cut(i)?;
                self.lateness.push(late);
                published += 1;
                if !on_cut(i) {
                    return Ok(published);
                }
            }
            if !options.looped {
                return Ok(published);
            }
        }
    }
}

/// How long before a cut's time the player stops sleeping and spins: a sleep may
/// overshoot by tens of microseconds (more on a busy machine), a spin does not.
const SPIN_BEFORE_DUE: Duration = Duration::from_micros(1500);

/// Waits until `due`: sleeps on the publisher's node until shortly before it, then
/// spins. The node's wait runs before every cut, even a zero one, so that SIGINT/SIGTERM
/// (whose handler its first call installs) end a play of cuts that are always due.
fn wait_until(publisher: &SegmentPublisher, due: Instant) -> Result<(), WriterWaitError> {
    let now = Instant::now();
    publisher.wait(due.saturating_duration_since(now + SPIN_BEFORE_DUE))?;
    while Instant::now() < due {
        std::hint::spin_loop();
    }
    Ok(())
}
