//! Statements of the volume the camera or a shape sits in ([`WithinCheck`]), checked when
//! the scene is compiled.
//!
//! risotto infers every medium from geometry: a volume is the interior of a closed shape,
//! and what surrounds a point is found by walking out of the scene from it
//! ([`CompiledScene::probe_stack`]). Formats that state media explicitly instead (Mitsuba
//! 3's sensor medium and shape `exterior`, pbrt-v4's `MediumInterface` outside medium) say
//! where the camera or a shape is; an importer writes that statement as a check, so that a
//! scene whose geometry says otherwise is an error naming both, never an image rendered
//! with the wrong medium around the camera or the shape.

use super::*;

/// The scene-file value of `within` stating that no medium surrounds the camera or shape
/// ([`WithinCheck::no_medium`]).
pub const NO_MEDIUM: &str = "no medium";

/// Points of a shape from which a "no medium" statement is checked ([`WithinCheck::no_medium`]).
const NO_MEDIUM_PROBES: usize = 64;

/// "The innermost volume around `subject` is the interior of one of `within`", or with
/// `no_medium`, "no medium surrounds `subject`": checked by [`Scene::compile`].
#[derive(Clone, Debug, PartialEq)]
pub struct WithinCheck {
    /// The camera (`None`) or the shape of this name.
    pub subject: Option<String>,
    /// Shape names; the innermost volume around the subject must be the interior of one of
    /// them. Empty (and `no_medium` false): the subject is in no volume.
    pub within: Vec<String>,
    /// The statement is "no medium surrounds the subject" instead (`within` is then empty):
    /// the innermost volume around it, if any, holds no medium (its material computes no
    /// interior, as a clear glass's), checked from points spread over a shape's surface
    /// (overlapping volumes). What formats that switch media at each crossing of a medium
    /// interface (Mitsuba 3) mean where they leave a medium unset.
    pub no_medium: bool,
    /// Where the statement was written (`within` in a scene file), for errors.
    pub at: Option<crate::diagnostics::Location>,
}

impl CompiledScene {
    /// The volumes around shape `shape` just outside it: the walk of [`Self::probe_stack`]
    /// from a point of its first primitive along its normal, its own crossings left out.
    pub fn stack_around(&self, shape: u32) -> Option<VolumeStack> {
        let prim =
            (0..self.geometry.num_flat_prims() as u32).find(|&p| self.shape_of_prim(p) == shape)?;
        let (point, normal) = self
            .geometry
            .sample_prim(prim, risotto_components::Vec2::splat(1.0 / 3.0));
        Some(self.probe_stack_excluding(point, -normal, Some(shape)))
    }

    /// [`Self::stack_around`] from about `count` points of shape `shape`: primitives evenly
    /// spread over its primitive list, and on each (a shape of few primitives: an analytic
    /// sphere is one) a grid of points over the primitive's sample square.
    pub fn stacks_around_spread(&self, shape: u32, count: usize) -> Vec<VolumeStack> {
        let count = count.max(1);
        let prims: Vec<u32> = (0..self.geometry.num_flat_prims() as u32)
            .filter(|&p| self.shape_of_prim(p) == shape)
            .collect();
        let step = prims.len().div_ceil(count).max(1);
        let per_prim = count.div_ceil(prims.len().max(1));
        let side = (per_prim as f64).sqrt().ceil() as usize;
        let mut stacks = Vec::new();
        for &prim in prims.iter().step_by(step) {
            for k in 0..side * side {
                let u = risotto_components::Vec2::new(
                    ((k % side) as f32 + 0.5) / side as f32,
                    ((k / side) as f32 + 0.5) / side as f32,
                );
                let (point, normal) = self.geometry.sample_prim(prim, u);
                stacks.push(self.probe_stack_excluding(point, -normal, Some(shape)));
            }
        }
        stacks
    }

    /// Runs one [`WithinCheck`]; the message of a failed one.
    pub(super) fn check_within(&self, check: &WithinCheck) -> Result<(), String> {
        let index = |name: &str| {
            self.shapes
                .iter()
                .position(|s| s.name == name)
                .map(|s| s as u32)
                .ok_or_else(|| format!("shape \"{name}\" does not exist"))
        };
        for name in &check.within {
            if !self.tracks_interior(index(name)?) {
                return Err(format!(
                    "shape \"{name}\" has no interior (its material neither transmits nor \
                     computes a volume), so nothing is within it"
                ));
            }
        }
        let (what, innermost) = match &check.subject {
            None => ("the camera".to_owned(), self.camera_stack.innermost()),
            Some(name) => {
                let s = index(name)?;
                let stack = self.stack_around(s).ok_or_else(|| {
                    format!("shape \"{name}\" is instanced or empty: it cannot be checked")
                })?;
                (format!("shape \"{name}\""), stack.innermost())
            }
        };
        if check.no_medium {
            let holds_medium = |shape: u32| {
                let info = &self.material_info[self.shapes[shape as usize].material as usize];
                info.hints.contains(InstanceHints::COMPUTES_INTERIOR)
            };
            // A shape may reach into a volume with part of its surface only (overlapping
            // volumes): the walk is repeated from points spread over its primitives.
            let innermost_volumes: Vec<u32> = match &check.subject {
                None => innermost.map(|e| e.shape).into_iter().collect(),
                Some(name) => {
                    let s = index(name)?;
                    self.stacks_around_spread(s, NO_MEDIUM_PROBES)
                        .iter()
                        .filter_map(|st| st.innermost().map(|e| e.shape))
                        .collect()
                }
            };
            return match innermost_volumes.into_iter().find(|&v| holds_medium(v)) {
                None => Ok(()),
                Some(v) => Err(format!(
                    "{what} is stated to be in no medium, but (at least part of) it lies in \
                     the interior of \"{}\", which holds a medium",
                    self.shapes[v as usize].name
                )),
            };
        }
        let innermost = innermost.map(|e| self.shapes[e.shape as usize].name.as_str());
        if innermost.is_some_and(|n| check.within.iter().any(|w| w == n))
            || (innermost.is_none() && check.within.is_empty())
        {
            return Ok(());
        }
        let stated = if check.within.is_empty() {
            "in no volume".to_owned()
        } else {
            let names: Vec<String> = check.within.iter().map(|n| format!("\"{n}\"")).collect();
            format!("within the interior of {}", names.join(" or "))
        };
        let found = match innermost {
            Some(n) => format!("the innermost volume around it is the interior of \"{n}\""),
            None => "it is in no volume (no closed shape with an interior encloses it)".to_owned(),
        };
        Err(format!("{what} is stated to be {stated}, but {found}"))
    }
}
