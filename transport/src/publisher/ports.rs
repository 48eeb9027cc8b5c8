//! The writer's iceoryx2 services and ports, with the never-block quality of service, and the
//! one way a segment is loaned, filled and sent.

use std::path::Path;

use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::prelude::{AllocationStrategy, Node};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use super::{PublishError, WriterCreateError, loan, shm};
use crate::protocol::{self, BLOCK_SIZE, Block128, EVENT_WRITER_GONE, SegmentHeader};
use crate::service::{self, EVENT_ID_MAX, Ipc, PUBLISHER_MAX_LOANED};

/// A publish-subscribe service of segments.
pub(crate) type SegmentFactory = PubSubFactory<Ipc, [Block128], SegmentHeader>;

/// Sizes of the scene's services, fixed when the first writer creates them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PortSettings {
    pub(crate) max_readers: usize,
    pub(crate) max_segments: usize,
    pub(crate) initial_blocks: usize,
}

/// A publisher port with the service it belongs to.
pub(crate) struct SegmentService {
    pub(crate) name: String,
    pub(crate) publisher: Publisher<Ipc, [Block128], SegmentHeader>,
    pub(crate) service: SegmentFactory,
    /// Most segments one snapshot may name on this stream: what the writer asked for, or
    /// less when the stream was created earlier for fewer.
    pub(crate) max_segments: usize,
    /// What this writer wrote into the pool's chunks, to give back the pages a smaller
    /// segment leaves unused ([`loan::ChunkPages`]).
    pub(crate) pages: loan::ChunkPages,
}

/// Loans, fills and sends one segment after checking shared-memory space.
///
/// The space check (a `statvfs`) runs before the loan when the loan grows the pool, and after
/// it otherwise, only for the part of the segment beyond the pages the loaned chunk is known to
/// hold already ([`loan::ChunkPages::backed`]): republishing a segment into a reused chunk
/// needs no new pages and costs no system call. A refused sample goes back to the pool unsent.
pub(crate) fn send_segment<E>(
    service: &mut SegmentService,
    shm_dir: &Path,
    header: SegmentHeader,
    len: usize,
    fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
) -> Result<(), PublishError>
where
    E: Into<Box<dyn std::error::Error + Send + Sync>>,
{
    let blocks = protocol::blocks_for(len).max(1);
    let payload_bytes = blocks
        .checked_mul(BLOCK_SIZE)
        .ok_or(PublishError::TooLarge { len })?;
    let in_current_pool = service.pages.fits_current_pool(blocks);
    if !in_current_pool {
        shm::ensure_free(shm_dir, payload_bytes as u64)?;
    }
    let mut sample = service
        .publisher
        .loan_slice_uninit(service.pages.loan_blocks(blocks))
        .map_err(|source| PublishError::Loan {
            service: service.name.clone(),
            source,
        })?;
    if in_current_pool {
        let payload = sample.payload_mut().as_mut_ptr().addr();
        let new_bytes = payload_bytes.saturating_sub(service.pages.backed(payload));
        if new_bytes > 0 {
            shm::ensure_free(shm_dir, new_bytes as u64)?;
        }
    }
    *sample.user_header_mut() = header;
    let sample = loan::fill_sample(sample, len, &mut service.pages, fill)
        .map_err(|e| PublishError::Fill(e.into()))?;
    sample.send().map_err(|source| PublishError::Send {
        service: service.name.clone(),
        source,
    })?;
    Ok(())
}

/// Opens or creates the segment stream with the never-block QoS and claims its only
/// publisher.
///
/// Never blocks: safe overflow (a reader that does not receive loses its oldest buffered
/// samples, never stalls the writer) and bounded borrows per subscriber. There is room for
/// one more subscriber than readers: the writer's own ([`super::retained`]).
///
/// A stream that readers keep alive from an earlier writer may have been sized for fewer
/// segments than `settings` asks for; it is used as it is and [`SegmentService::max_segments`]
/// says what it supports (the services of a scene cannot be resized while anyone holds them).
pub(crate) fn open_segment_port(
    node: &Node<Ipc>,
    name: &str,
    settings: PortSettings,
) -> Result<SegmentService, WriterCreateError> {
    let service_name = crate::service::service_name(name)?;
    let stream = || {
        node.service_builder(&service_name)
            .publish_subscribe::<[Block128]>()
            .user_header::<SegmentHeader>()
            .max_publishers(1)
            .max_subscribers(settings.max_readers + 1)
            .max_nodes(settings.max_readers + 2)
            .history_size(0)
            .enable_safe_overflow(true)
    };
    let opened = stream()
        .subscriber_max_buffer_size(service::stream_buffer_size(settings.max_segments))
        .subscriber_max_borrowed_samples(service::stream_max_borrowed(settings.max_segments))
        .open_or_create();
    let service = match opened {
        Err(PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(
            PublishSubscribeOpenError::DoesNotSupportRequestedMinBufferSize
            | PublishSubscribeOpenError::DoesNotSupportRequestedMinSubscriberBorrowedSamples,
        )) => stream()
            .open()
            .map_err(|e| crate::service::service_failure(name, e))?,
        opened => opened.map_err(|e| crate::service::service_failure(name, e))?,
    };
    let config = service.static_config();
    let max_segments = service::stream_segments_supported(
        config.subscriber_max_buffer_size(),
        config.subscriber_max_borrowed_samples(),
    )
    .min(settings.max_segments);
    let publisher = service
        .publisher_builder()
        .max_loaned_samples(PUBLISHER_MAX_LOANED)
        .initial_max_slice_len(settings.initial_blocks)
        .allocation_strategy(AllocationStrategy::PowerOfTwo)
        .create()
        .map_err(|e| match e {
            PublisherCreateError::ExceedsMaxSupportedPublishers => {
                WriterCreateError::AlreadyRunning {
                    scene: scene_of(name),
                }
            }
            e => crate::service::port_failure(name, e).into(),
        })?;
    Ok(SegmentService {
        name: name.to_owned(),
        publisher,
        service,
        max_segments,
        pages: loan::ChunkPages::new(settings.initial_blocks),
    })
}

/// `ygg/<scene>/...` -> `<scene>`.
fn scene_of(service: &str) -> String {
    service.split('/').nth(1).unwrap_or(service).to_owned()
}

/// Opens or creates an event service. On the writer -> readers service, a writer that drops
/// or is found dead emits [`EVENT_WRITER_GONE`].
pub(crate) fn open_event_service(
    node: &Node<Ipc>,
    name: &str,
    max_readers: usize,
    to_readers: bool,
) -> Result<EventFactory<Ipc>, WriterCreateError> {
    let mut builder = node
        .service_builder(&crate::service::service_name(name)?)
        .event()
        .max_nodes(max_readers + 2)
        .max_listeners(max_readers + 2)
        .max_notifiers(max_readers + 2)
        .event_id_max_value(EVENT_ID_MAX);
    if to_readers {
        builder = builder
            .notifier_dead_event(EVENT_WRITER_GONE)
            .notifier_dropped_event(EVENT_WRITER_GONE);
    }
    builder
        .open_or_create()
        .map_err(|e| WriterCreateError::from(crate::service::service_failure(name, e)))
}
