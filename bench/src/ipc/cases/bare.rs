//! `bare_iceoryx2`: the physical floor every latency target is a ratio to.

use super::super::bare::BarePublisher;
use super::super::child::Readers;
use super::super::clock::unix_ns;
use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::{Row, median, median_p99_us};
use super::context::{Ctx, in_scene};
use super::drive::{ATTACH_TIMEOUT, EXIT_GRACE, Jitter, collect_seen, reader_args};

/// A bare iceoryx2 publisher (this process) and subscriber process, payloads of `len`
/// bytes, `samples` publishes timed from the publish call to the subscriber holding them.
pub(super) fn case_bare(ctx: &mut Ctx, len: usize, samples: usize) -> Res<Row> {
    in_scene(ctx, "bare", |ctx, scene| {
        let publisher = BarePublisher::new(&scene.name, &scene.prefix, len, 2)?;
        let mut readers = Readers::spawn(1, scene, &reader_args("bare", None), ATTACH_TIMEOUT)?;
        let warmup = 5;
        let mut jitter = Jitter(0x2545_F491_4F6C_DD1D);
        // (seq, before the call, call duration)
        let mut sent = Vec::with_capacity(samples);
        for seq in 0..(warmup + samples) as u64 {
            check_interrupted()?;
            std::thread::sleep(jitter.apply(ctx.plan.gap));
            let t0 = unix_ns();
            publisher.publish(seq)?;
            let t1 = unix_ns();
            if seq >= warmup as u64 {
                sent.push((seq, t0, t1 - t0));
            }
        }
        std::thread::sleep(ctx.plan.gap * 4);
        let seen = collect_seen(&mut readers)?;
        readers.finish(EXIT_GRACE)?;
        drop(publisher);
        let mut visible = Vec::with_capacity(sent.len());
        let mut cpu = Vec::with_capacity(sent.len());
        for (seq, t0, _) in &sent {
            if let Some([held, _, c]) = seen[0].get(seq) {
                visible.push(held.saturating_sub(*t0) as f64);
                cpu.push(*c as f64);
            }
        }
        let calls: Vec<f64> = sent.iter().map(|(_, _, d)| *d as f64).collect();
        let mut row = Row::latency(
            "bare_iceoryx2",
            "the floor: bare iceoryx2 publisher and subscriber processes (no Yggdrasil code), payload the size of the office's AGENTS segment, event wake-up, publish call → subscriber holds the bytes",
            &visible,
        )
        .with("publish_call_us", median_p99_us(&calls).0)
        .with("bytes_per_publish", len as f64)
        .with("reader_cpu_us", median(&cpu) / 1e3);
        if visible.len() < sent.len() {
            row.note = format!(
                "{} of {} samples never seen",
                sent.len() - visible.len(),
                sent.len()
            );
        }
        Ok(row)
    })
}
