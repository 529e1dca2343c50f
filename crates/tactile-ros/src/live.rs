//! The live view: the same channels as an MCAP file of results, served over
//! the Foxglove WebSocket protocol (the `foxglove` SDK's server), so a
//! researcher opens Foxglove on `ws://HOST:PORT` and watches the decision,
//! the mask, the depth and the direction as the pipeline runs.
//!
//! The pipeline never waits for a viewer: frames are encoded only while a
//! viewer is subscribed, and handed to the server's thread through a queue
//! of [`LIVE_QUEUE`] frames; when it is full the frame is dropped and
//! counted ([`LiveView::dropped`]).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::{Arc, Mutex};

use foxglove::{ChannelBuilder, Context, RawChannel, WebSocketServer};

use crate::results::{FrameMessages, Topic};
use crate::{Error, Result};

/// Frames that may wait for the server's thread; more are dropped.
pub const LIVE_QUEUE: usize = 4;

/// A Foxglove WebSocket server with the result channels.
pub struct LiveView {
    address: String,
    host: String,
    port: u16,
    channels: Arc<BTreeMap<Topic, Arc<RawChannel>>>,
    queue: Option<SyncSender<FrameMessages>>,
    worker: Option<std::thread::JoinHandle<()>>,
    dropped: Arc<AtomicU64>,
    sent: Arc<AtomicU64>,
    server: Mutex<Option<foxglove::WebSocketServerHandle>>,
    /// The channels' context: the server holds it weakly, so it lives here.
    _context: Arc<Context>,
}

/// `HOST:PORT` split; port 0 picks a free one.
fn parse_address(address: &str) -> Result<(String, u16)> {
    let bad = |why: &str| Error::Address {
        address: address.into(),
        message: format!("{why}; give HOST:PORT such as 127.0.0.1:8765"),
    };
    let (host, port) = address.rsplit_once(':').ok_or_else(|| bad("no port"))?;
    let port: u16 = port
        .parse()
        .map_err(|_| bad("the port is not a number from 0 to 65535"))?;
    let host = host.trim_start_matches('[').trim_end_matches(']');
    if host.is_empty() {
        return Err(bad("no host"));
    }
    Ok((host.to_string(), port))
}

/// Refuse a wait for a viewer that is not a finite number of seconds >= 0,
/// naming the argument `what` (`tactile run --view-wait`,
/// [`crate::RunSession::open`], [`LiveView::wait_for_viewer`]).
pub fn check_wait_seconds(what: &str, seconds: f64) -> Result<()> {
    if seconds.is_finite() && seconds >= 0.0 {
        return Ok(());
    }
    Err(tactile_core::Error::Invalid(format!(
        "{what}: seconds must be a finite number >= 0, got {seconds:?}"
    ))
    .into())
}

impl LiveView {
    /// Serve the channels of `topics` at `address` (`HOST:PORT`; port 0
    /// picks a free one, see [`LiveView::port`]): a run's are those it can
    /// write ([`Topic::written_by`]), so a viewer lists no topic that
    /// stays empty; messages of other topics are not sent.
    pub fn serve(address: &str, topics: &[Topic]) -> Result<Self> {
        let (host, port) = parse_address(address)?;
        let fail = |message: String| Error::Live {
            address: address.into(),
            message,
        };
        let ctx = Context::new();
        let mut channels = BTreeMap::new();
        for &topic in topics {
            let s = topic.schema();
            let schema = foxglove::Schema::new(s.name, "ros2msg", s.text.into_bytes());
            let channel = ChannelBuilder::new(topic.name())
                .message_encoding("cdr")
                .schema(schema)
                .context(&ctx)
                .build_raw()
                .map_err(|e| fail(e.to_string()))?;
            channels.insert(topic, channel);
        }
        let server = WebSocketServer::new()
            .name("tactile-rs")
            .bind(host.clone(), port)
            .context(&ctx)
            .start_blocking()
            .map_err(|e| fail(e.to_string()))?;
        let port = server.port();
        let channels = Arc::new(channels);
        let (tx, rx) = std::sync::mpsc::sync_channel::<FrameMessages>(LIVE_QUEUE);
        let sent = Arc::new(AtomicU64::new(0));
        let worker = {
            let channels = Arc::clone(&channels);
            let sent = Arc::clone(&sent);
            std::thread::spawn(move || {
                for frame in rx {
                    let meta = foxglove::PartialMetadata {
                        log_time: u64::try_from(frame.stamp_ns).ok(),
                    };
                    for (topic, data) in &frame.messages {
                        if let Some(c) = channels.get(topic) {
                            c.log_with_meta(data, meta);
                        }
                    }
                    sent.fetch_add(1, Ordering::Relaxed);
                }
            })
        };
        Ok(Self {
            address: address.into(),
            host,
            port,
            channels,
            queue: Some(tx),
            worker: Some(worker),
            dropped: Arc::new(AtomicU64::new(0)),
            sent,
            server: Mutex::new(Some(server)),
            _context: ctx,
        })
    }

    /// The address asked for.
    pub fn address(&self) -> &str {
        &self.address
    }

    /// The port served (the one picked when 0 was asked for).
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Where Foxglove connects: `ws://HOST:PORT` with the port served.
    pub fn url(&self) -> String {
        match self.host.contains(':') {
            true => format!("ws://[{}]:{}", self.host, self.port),
            false => format!("ws://{}:{}", self.host, self.port),
        }
    }

    /// Wait up to `seconds` (at most an hour) for a viewer to subscribe, so
    /// a recorded source is watched from its first frame; true when one did.
    /// Ctrl-C ends the wait as an interrupt. A wait that is not a finite
    /// number >= 0 is refused.
    pub fn wait_for_viewer(&self, seconds: f64) -> Result<bool> {
        check_wait_seconds("wait_for_viewer", seconds)?;
        let until = std::time::Instant::now()
            + std::time::Duration::from_secs_f64(seconds.clamp(0.0, 3600.0));
        while !self.watched() {
            if std::time::Instant::now() >= until {
                return Ok(false);
            }
            tactile_core::interrupt::check()?;
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        Ok(true)
    }

    /// Whether a viewer is subscribed to any channel: frames are encoded
    /// only then.
    pub fn watched(&self) -> bool {
        self.channels.values().any(|c| c.has_sinks())
    }

    /// Hand one frame's messages to the server without waiting: a full
    /// queue drops it (counted).
    pub fn publish(&self, frame: FrameMessages) {
        let Some(q) = &self.queue else { return };
        match q.try_send(frame) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Frames dropped because the server's thread was behind.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Frames handed to the server.
    pub fn sent(&self) -> u64 {
        self.sent.load(Ordering::Relaxed)
    }

    /// Send what is queued, then stop the server.
    pub fn close(&mut self) {
        self.queue = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
        if let Ok(mut s) = self.server.lock()
            && let Some(server) = s.take()
        {
            server.stop().wait_blocking();
        }
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        self.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_are_checked() {
        assert_eq!(
            parse_address("127.0.0.1:8765").unwrap(),
            ("127.0.0.1".into(), 8765)
        );
        assert_eq!(parse_address("[::1]:0").unwrap(), ("::1".into(), 0));
        for bad in ["8765", "host:", "host:99999", ":8765"] {
            let e = parse_address(bad).unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains("HOST:PORT"), "{e}");
        }
    }
}
