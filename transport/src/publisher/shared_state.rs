//! The state a scene's publisher shares with its helper thread ([`Inner`], behind a mutex:
//! the segment stream, the events notifier) and the lock both sides take.

use std::sync::{Mutex, MutexGuard, PoisonError};

use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{CallbackProgression, EventId};
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;

use super::PublishError;
use super::ports::{SegmentService, send_segment};
use super::retained::{Retained, RetainedSample};
use crate::protocol;
use crate::service::Ipc;

/// The segment stream's publisher and the writer's hold on what it sent.
pub(super) struct Stream {
    pub(super) port: SegmentService,
    pub(super) retained: Retained,
}

/// State shared with the helper thread.
pub(crate) struct Inner {
    /// `None` once the writer is closing.
    pub(super) stream: Option<Stream>,
    pub(super) events_notifier: Notifier<Ipc>,
    pub(super) _events: EventFactory<Ipc>,
}

impl Inner {
    /// Connects new subscribers to the segment stream.
    pub(crate) fn update_connections(&self) {
        if let Some(stream) = &self.stream {
            // A failing connection is retried on the next send; nothing to report here.
            let _ = stream.port.publisher.update_connections();
        }
    }

    /// The nodes of the readers connected now (of the stream's subscribers, all but the
    /// writer's own).
    pub(crate) fn reader_nodes(&self) -> Vec<UniqueNodeId> {
        let Some(s) = &self.stream else {
            return Vec::new();
        };
        let config = s.port.service.dynamic_config();
        let mut writers = Vec::new();
        config.list_publishers(|p| {
            writers.push(p.node_id);
            CallbackProgression::Continue
        });
        let mut readers = Vec::new();
        config.list_subscribers(|sub| {
            if !writers.contains(&sub.node_id) && !readers.contains(&sub.node_id) {
                readers.push(sub.node_id);
            }
            CallbackProgression::Continue
        });
        readers
    }

    /// Readers connected to the scene now (the stream's subscribers but the writer's own).
    pub(crate) fn reader_count(&self) -> usize {
        self.stream.as_ref().map_or(0, |s| {
            s.port
                .service
                .dynamic_config()
                .number_of_subscribers()
                .saturating_sub(1)
        })
    }

    /// Sends a catch-up copy of `sample` on the stream (and drops the writer's own copy of
    /// it at once).
    pub(crate) fn send_copy(
        &mut self,
        sample: &RetainedSample,
        shm_dir: &std::path::Path,
    ) -> Result<(), PublishError> {
        let stream = self.stream.as_mut().ok_or(PublishError::Closed)?;
        let mut header = *sample.header();
        header.flags |= protocol::FLAG_CATCH_UP;
        let bytes = sample.bytes();
        send_segment(&mut stream.port, shm_dir, header, bytes.len(), |buf| {
            buf.copy_from_slice(bytes);
            Ok::<_, std::convert::Infallible>(())
        })?;
        stream.retained.receive(None);
        Ok(())
    }

    /// The samples of the current snapshot, its manifest last (empty before the first).
    pub(crate) fn current_snapshot(&self) -> Vec<RetainedSample> {
        self.stream
            .as_ref()
            .map_or_else(Vec::new, |s| s.retained.snapshot())
    }

    /// Wakes the readers with `event`.
    pub(crate) fn notify(&self, event: EventId) {
        // Readers without a listener (or none at all) are no error for the writer.
        let _ = self.events_notifier.notify_with_custom_event_id(event);
    }
}

/// The state shared with the helper thread, locked.
pub(crate) fn lock(inner: &Mutex<Inner>) -> MutexGuard<'_, Inner> {
    // A panic in the helper thread leaves the ports intact; keep using them.
    inner.lock().unwrap_or_else(PoisonError::into_inner)
}
