//! Decoding ahead on a worker thread: while the device draws the current
//! frame, the maps of the sample the eye is moving towards are decoded
//! straight into the slot the sample will play from (host-written arrays,
//! lavapipe: no copy at all) or into staging buffers the worker borrows
//! from the pool (the frame that needs them then records their upload).
//! The worker owns its own map source (and decode cache); buffers and
//! lent slots travel by channel.

use super::source::{MapLayer, MapSource};
use crate::backend::Buffer;
use crate::backend::host_image::HostElement;
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

/// Work for the decode worker.
pub enum Job {
    /// One map into a staging buffer.
    Staging(MapKey, Buffer),
    /// Every layer of one sample straight into its slot: each map's key
    /// and lent array element, the finest `drop` levels left out.
    Slot {
        maps: Vec<(MapKey, HostElement)>,
        drop: u32,
    },
}

impl Job {
    /// The maps a job decodes.
    fn keys(&self) -> Vec<&MapKey> {
        match self {
            Job::Staging(key, _) => vec![key],
            Job::Slot { maps, .. } => maps.iter().map(|(k, _)| k).collect(),
        }
    }

    /// The key a job is known by (a slot job by its first map's).
    fn key(&self) -> Option<&MapKey> {
        self.keys().first().copied()
    }

    /// Runs the job; each map's decode time (wall clock, ms).
    fn run(&mut self, source: &mut MapSource) -> anyhow::Result<Vec<f64>> {
        match self {
            Job::Staging(key, buffer) => {
                decode_into(source, key, buffer)?;
                Ok(vec![source.last_read_ms])
            }
            Job::Slot { maps, drop } => {
                let mut ms = Vec::with_capacity(maps.len());
                for (key, slot) in maps {
                    let k = (key.object.as_str(), key.layer, key.resolution, key.sample);
                    source.read_into_slot(k, slot, *drop)?;
                    ms.push(source.last_read_ms);
                }
                Ok(ms)
            }
        }
    }
}

struct Decoded {
    job: Job,
    ok: bool,
    /// Each map's decode time.
    ms: Vec<f64>,
}

pub struct Prefetcher {
    jobs: Option<Sender<Job>>,
    results: Receiver<Decoded>,
    worker: Option<JoinHandle<()>>,
    in_flight: Vec<MapKey>,
    ready: Vec<Decoded>,
    /// Buffers back from failed decodes or dropped results, for the pool.
    spare: Vec<Buffer>,
    /// Each map decoded since [`Prefetcher::drain_decode_ms`] last ran: its
    /// wall time on the worker, beside whatever else the cores ran.
    decode_ms: Vec<f64>,
}

/// The worker's loop: run each job and hand it back; when no job waits,
/// warm the coarse levels of the next samples of the maps it handed over
/// (`MapSource::warm_ahead`), one map per turn, so warming never delays a
/// job.
fn worker(source: &mut MapSource, inbox: &Receiver<Job>, outbox: &Sender<Decoded>) {
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
        let Some(mut job) = job else { return };
        // A failed job is simply not used: the frame reads the map itself
        // and reports the error there.
        let result = job.run(source);
        let ok = result.is_ok();
        if ok {
            for key in job.keys() {
                let map = (key.object.clone(), key.layer);
                if !to_warm.contains(&map) {
                    to_warm.push(map);
                }
            }
        }
        let ms = result.unwrap_or_default();
        if outbox.send(Decoded { job, ok, ms }).is_err() {
            return;
        }
    }
}

/// Decoded staging maps kept waiting at most (older ones are dropped;
/// slot jobs are never dropped: their slots wait for them).
const READY_MAX: usize = 8;

impl Prefetcher {
    pub fn new(mut source: MapSource) -> Self {
        let (jobs, inbox) = channel::<Job>();
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
            decode_ms: Vec::new(),
        }
    }

    fn collect(&mut self, wait_for: Option<&MapKey>) {
        loop {
            let next = match wait_for {
                Some(k) if self.in_flight.contains(k) => self.results.recv().ok(),
                _ => self.results.try_recv().ok(),
            };
            let Some(done) = next else { return };
            if let Some(key) = done.job.key() {
                self.in_flight.retain(|k| k != key);
            }
            if done.ok {
                self.decode_ms.extend(&done.ms);
            }
            match done.job {
                Job::Staging(_, buffer) if !done.ok => self.spare.push(buffer),
                _ => self.ready.push(done),
            }
            let staged = |d: &Decoded| matches!(d.job, Job::Staging(..));
            if self.ready.iter().filter(|d| staged(d)).count() > READY_MAX
                && let Some(i) = self.ready.iter().position(staged)
                && let Job::Staging(_, buffer) = self.ready.remove(i).job
            {
                self.spare.push(buffer);
            }
        }
    }

    /// Takes the finished job known by `key`, waiting for it when it is
    /// still running (`wait`), with whether it succeeded and the worker's
    /// time.
    fn take_job(&mut self, key: &MapKey, wait: bool) -> Option<Decoded> {
        self.collect(wait.then_some(key));
        let i = self.ready.iter().position(|d| d.job.key() == Some(key))?;
        Some(self.ready.swap_remove(i))
    }

    /// The staging buffer holding `key` if it was decoded ahead (waiting
    /// for it when it is still being decoded), with the worker's time.
    pub fn take(&mut self, key: &MapKey) -> Option<(Buffer, f64)> {
        match self.take_job(key, true)? {
            Decoded {
                job: Job::Staging(_, buffer),
                ms,
                ..
            } => Some((buffer, ms.iter().sum())),
            _ => None,
        }
    }

    /// Whether the slot job known by `key` (its first map) finished, and
    /// how: `Some(Ok(ms))` filled, `Some(Err(()))` failed, None still
    /// running (never with `wait`, unless the worker is gone). Its slots
    /// are given back either way.
    pub fn take_slot(&mut self, key: &MapKey, wait: bool) -> Option<Result<f64, ()>> {
        let done = self.take_job(key, wait)?;
        Some(if done.ok {
            Ok(done.ms.iter().sum())
        } else {
            Err(())
        })
    }

    /// The decode times of the maps finished since the last call.
    pub fn drain_decode_ms(&mut self) -> Vec<f64> {
        self.collect(None);
        std::mem::take(&mut self.decode_ms)
    }

    /// Whether `key` is decoded or on its way.
    pub fn has(&mut self, key: &MapKey) -> bool {
        self.collect(None);
        self.in_flight.contains(key) || self.ready.iter().any(|d| d.job.key() == Some(key))
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

    /// Hands `job` to the worker; gives it back when the worker cannot
    /// take it.
    pub fn request(&mut self, job: Job) -> Option<Job> {
        let (Some(jobs), Some(key)) = (&self.jobs, job.key().cloned()) else {
            return Some(job);
        };
        match jobs.send(job) {
            Ok(()) => {
                self.in_flight.push(key);
                None
            }
            Err(e) => Some(e.0),
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
