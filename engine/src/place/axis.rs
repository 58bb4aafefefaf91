//! Which lines of a dense viewpoint grid `engine place` chooses: the
//! azimuth lines of a 1D orbit, or the elevation rings of a 2D one (every
//! ring keeps all azimuth lines: the grid stays azimuths × rings).

use anyhow::{Result, bail};
use inference::scene::{Orbit, Scene};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    Azimuth,
    Rings,
}

impl Axis {
    /// An error when the scene has no such lines to choose from.
    pub fn check(self, scene: &Scene) -> Result<()> {
        let rings = scene.orbit.rings;
        match self {
            Axis::Azimuth if rings > 1 => bail!(
                "{}: [orbit] has {rings} rings: `engine place` places the azimuth lines of a 1D \
                 orbit, with --rings the rings of a 2D one, or with --grid both",
                scene.origin
            ),
            Axis::Rings if rings < 2 => bail!(
                "{}: --rings: [orbit] has one ring (expected rings ≥ 2 to choose from)",
                scene.origin
            ),
            _ => Ok(()),
        }
    }

    /// Dense lines along this axis.
    pub fn lines(self, orbit: &Orbit) -> u32 {
        match self {
            Axis::Azimuth => orbit.samples,
            Axis::Rings => orbit.rings,
        }
    }

    /// Samples each line holds (the other axis's lines).
    pub fn samples_per_line(self, orbit: &Orbit) -> u32 {
        match self {
            Axis::Azimuth => orbit.rings.max(1),
            Axis::Rings => orbit.samples.max(1),
        }
    }

    /// Where line `line` sits along the axis, degrees.
    pub fn position_deg(self, orbit: &Orbit, line: u32) -> f32 {
        match self {
            Axis::Azimuth => orbit.angle_deg(line),
            Axis::Rings => orbit.ring_elevation(line),
        }
    }

    /// Where the view that scores the interval split at `at` sits: half
    /// a line past it, between dense lines, so no dense solve saw it (see
    /// [`super::probe_azimuth`]).
    pub fn probe_deg(self, orbit: &Orbit, at: u32) -> f32 {
        match self {
            Axis::Azimuth => super::probe_azimuth(orbit, at),
            Axis::Rings => 0.5 * (orbit.ring_elevation(at) + orbit.ring_elevation(at + 1)),
        }
    }

    /// The word for a line along this axis, in reports.
    pub fn noun(self) -> &'static str {
        match self {
            Axis::Azimuth => "lines",
            Axis::Rings => "rings",
        }
    }
}

/// What `engine place` places: one axis's lines, or both axes of a 2D
/// grid together (`--grid`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Placing {
    Azimuth,
    Rings,
    Grid,
}

impl Placing {
    /// The one axis placed; None for the grid.
    pub fn axis(self) -> Option<Axis> {
        match self {
            Placing::Azimuth => Some(Axis::Azimuth),
            Placing::Rings => Some(Axis::Rings),
            Placing::Grid => None,
        }
    }

    /// An error when the scene has nothing of this kind to choose from.
    pub fn check(self, scene: &Scene) -> Result<()> {
        match self.axis() {
            Some(axis) => axis.check(scene),
            None => {
                let o = &scene.orbit;
                if o.rings < 2 || o.samples < 2 {
                    bail!(
                        "{}: --grid: [orbit] has {} azimuth lines × {} rings (expected at least \
                         2 of each to choose from)",
                        scene.origin,
                        o.samples,
                        o.rings.max(1)
                    );
                }
                Ok(())
            }
        }
    }

    /// The words for what is placed, in reports.
    pub fn noun(self) -> &'static str {
        match self.axis() {
            Some(axis) => axis.noun(),
            None => "lines × rings",
        }
    }
}
