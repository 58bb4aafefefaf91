//! Decoding ahead on a worker thread: while the device draws the current
//! frame, the maps of the sample the eye is moving towards are decoded
//! straight into staging buffers the worker borrows from the pool, so the
//! frame that needs them only records their upload. The worker owns its
//! own map source (and decode cache); buffers travel by channel.

use super::source::{MapLayer, MapSource};
use crate::backend::Buffer;
use half::f16;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::thread::JoinHandle;

/// Which map of which reflector at which sample.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapKey {
    pub object: String,
    pub layer: MapLayer,
    pub resolution: u32,
    pub sample: u32,
}

/// Decodes `key` from `source` into the start of `buffer` (RGBA f16, the
/// upload layout).
pub fn decode_into(
    source: &mut MapSource,
    key: &MapKey,
    buffer: &mut Buffer,
) -> anyhow::Result<()> {
    let halves = key.layer.layout(key.resolution).len() * 4;
    let bytes = buffer.mapped_mut()?;
    let Some(bytes) = bytes.get_mut(..halves * 2) else {
        anyhow::bail!(
            "a staging buffer of {} bytes holds no {}-texel map",
            bytes.len(),
            halves / 4
        );
    };
    let out: &mut [f16] = bytemuck::try_cast_slice_mut(bytes)
        .map_err(|e| anyhow::anyhow!("staging buffer not f16-aligned: {e}"))?;
    source.read(&key.object, key.layer, key.resolution, key.sample, out)
}

struct Decoded {
    key: MapKey,
    buffer: Buffer,
    ok: bool,
    ms: f64,
}

pub struct Prefetcher {
    jobs: Option<Sender<(MapKey, Buffer)>>,
    results: Receiver<Decoded>,
    worker: Option<JoinHandle<()>>,
    in_flight: Vec<MapKey>,
    ready: Vec<(MapKey, Buffer, f64)>,
    /// Buffers back from failed decodes or dropped results, for the pool.
    spare: Vec<Buffer>,
}

/// The worker's loop: decode each request into its buffer and hand it
/// back; when no request waits, warm the coarse levels of the next samples
/// of the maps it handed over (`MapSource::warm_ahead`), one map per turn,
/// so warming never delays a request.
fn worker(source: &mut MapSource, inbox: &Receiver<(MapKey, Buffer)>, outbox: &Sender<Decoded>) {
    let mut to_warm: Vec<(String, MapLayer)> = Vec::new();
    loop {
        let job = match to_warm.is_empty() {
            true => inbox.recv().ok(),
            false => match inbox.try_recv() {
                Ok(job) => Some(job),
                Err(TryRecvError::Empty) => {
                    let (object, layer) = to_warm.remove(0);
                    source.warm_ahead(&object, layer);
                    continue;
                }
                Err(TryRecvError::Disconnected) => None,
            },
        };
        let Some((key, mut buffer)) = job else { return };
        // A failed prefetch is simply not used: the frame reads the map
        // itself and reports the error there.
        let ok = decode_into(source, &key, &mut buffer).is_ok();
        let map = (key.object.clone(), key.layer);
        if ok && !to_warm.contains(&map) {
            to_warm.push(map);
        }
        let ms = source.last_read_ms;
        if outbox
            .send(Decoded {
                key,
                buffer,
                ok,
                ms,
            })
            .is_err()
        {
            return;
        }
    }
}

/// Decoded maps kept waiting at most (older ones are dropped).
const READY_MAX: usize = 8;

impl Prefetcher {
    pub fn new(mut source: MapSource) -> Self {
        let (jobs, inbox) = channel::<(MapKey, Buffer)>();
        let (outbox, results) = channel();
        let worker = std::thread::Builder::new()
            .name("map-prefetch".into())
            .spawn(move || worker(&mut source, &inbox, &outbox))
            .ok();
        Self {
            jobs: worker.as_ref().map(|_| jobs),
            results,
            worker,
            in_flight: Vec::new(),
            ready: Vec::new(),
            spare: Vec::new(),
        }
    }

    fn collect(&mut self, wait_for: Option<&MapKey>) {
        loop {
            let next = match wait_for {
                Some(k) if self.in_flight.contains(k) => self.results.recv().ok(),
                _ => self.results.try_recv().ok(),
            };
            let Some(done) = next else { return };
            self.in_flight.retain(|k| *k != done.key);
            if !done.ok {
                self.spare.push(done.buffer);
                continue;
            }
            self.ready.push((done.key, done.buffer, done.ms));
            if self.ready.len() > READY_MAX {
                let (_, buffer, _) = self.ready.remove(0);
                self.spare.push(buffer);
            }
        }
    }

    /// The staging buffer holding `key` if it was decoded ahead (waiting
    /// for it when it is still being decoded), with the worker's time.
    pub fn take(&mut self, key: &MapKey) -> Option<(Buffer, f64)> {
        self.collect(Some(key));
        let i = self.ready.iter().position(|(k, ..)| k == key)?;
        let (_, buffer, ms) = self.ready.swap_remove(i);
        Some((buffer, ms))
    }

    /// Whether `key` is decoded or on its way.
    pub fn has(&mut self, key: &MapKey) -> bool {
        self.collect(None);
        self.in_flight.contains(key) || self.ready.iter().any(|(k, ..)| k == key)
    }

    /// Waits until the worker has finished every request (so it no longer
    /// competes with rendering, e.g. before timing frames).
    pub fn wait_idle(&mut self) {
        while let Some(key) = self.in_flight.first().cloned() {
            let before = self.in_flight.len();
            self.collect(Some(&key));
            if self.in_flight.len() == before {
                // The worker is gone: nothing more will arrive.
                self.in_flight.clear();
            }
        }
    }

    /// Decodes `key` into `buffer` ahead of need; returns the buffer when
    /// the worker cannot take it.
    pub fn request(&mut self, key: MapKey, buffer: Buffer) -> Option<Buffer> {
        let Some(jobs) = &self.jobs else {
            return Some(buffer);
        };
        match jobs.send((key.clone(), buffer)) {
            Ok(()) => {
                self.in_flight.push(key);
                None
            }
            Err(e) => Some(e.0.1),
        }
    }

    /// Buffers the pool may have back.
    pub fn reclaim(&mut self) -> Vec<Buffer> {
        self.collect(None);
        std::mem::take(&mut self.spare)
    }
}

impl Drop for Prefetcher {
    fn drop(&mut self) {
        self.jobs = None; // ends the worker's loop
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}
