//! Decoding ahead on a worker thread: while the device draws the current
//! frame, the maps of the sample the eye is moving towards are decoded, so
//! the frame that needs them only copies them into staging. The worker owns
//! its own map source (and decode cache); results come back by channel.

use super::source::{MapLayer, MapSource};
use half::f16;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;

/// Which map of which reflector at which sample.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapKey {
    pub object: String,
    pub layer: MapLayer,
    pub resolution: u32,
    pub sample: u32,
}

struct Decoded {
    key: MapKey,
    texels: anyhow::Result<Vec<f16>>,
    ms: f64,
}

pub struct Prefetcher {
    jobs: Option<Sender<MapKey>>,
    results: Receiver<Decoded>,
    worker: Option<JoinHandle<()>>,
    in_flight: Vec<MapKey>,
    ready: Vec<(MapKey, Vec<f16>, f64)>,
}

/// Decoded maps kept waiting at most (older ones are dropped).
const READY_MAX: usize = 8;

impl Prefetcher {
    pub fn new(mut source: MapSource) -> Self {
        let (jobs, inbox) = channel::<MapKey>();
        let (outbox, results) = channel();
        let worker = std::thread::Builder::new()
            .name("map-prefetch".into())
            .spawn(move || {
                for key in inbox {
                    let layout = inference::solve::layout::TextureLayout::full_chain(
                        key.layer.shape(key.resolution),
                    );
                    let mut texels = vec![f16::ZERO; layout.len() * 4];
                    let read = source.read(
                        &key.object,
                        key.layer,
                        key.resolution,
                        key.sample,
                        &mut texels,
                    );
                    let ms = source.last_read_ms;
                    if outbox
                        .send(Decoded {
                            key,
                            texels: read.map(|_| texels),
                            ms,
                        })
                        .is_err()
                    {
                        break;
                    }
                }
            })
            .ok();
        Self {
            jobs: worker.as_ref().map(|_| jobs),
            results,
            worker,
            in_flight: Vec::new(),
            ready: Vec::new(),
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
            // A failed prefetch is simply not used: the frame reads the map
            // itself and reports the error there.
            if let Ok(texels) = done.texels {
                self.ready.push((done.key, texels, done.ms));
                if self.ready.len() > READY_MAX {
                    self.ready.remove(0);
                }
            }
        }
    }

    /// The decoded texels of `key` if it was prefetched (waiting for it when
    /// it is still being decoded), with the worker's decode time.
    pub fn take(&mut self, key: &MapKey) -> Option<(Vec<f16>, f64)> {
        self.collect(Some(key));
        let i = self.ready.iter().position(|(k, ..)| k == key)?;
        let (_, texels, ms) = self.ready.swap_remove(i);
        Some((texels, ms))
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

    /// Asks for `key` unless it is already decoded or on its way.
    pub fn request(&mut self, key: MapKey) {
        self.collect(None);
        if self.in_flight.contains(&key) || self.ready.iter().any(|(k, ..)| *k == key) {
            return;
        }
        if let Some(jobs) = &self.jobs
            && jobs.send(key.clone()).is_ok()
        {
            self.in_flight.push(key);
        }
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
