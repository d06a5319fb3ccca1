//! The per-ray volume stack: which volumes a ray is inside.
//!
//! The renderer, not the volume integrators, keeps this bookkeeping (the seed: "the renderer
//! has automatically kept track of the fact that a volume has been entered, but has not yet
//! been exited"). A ray that crosses a surface with the transmit bit set *enters* the surface's
//! interior when it crosses the front face and *leaves* it when it crosses the back face;
//! reflected rays keep the stack they had.
//!
//! Nested dielectrics follow priorities (Schmidt and Budge, "Simple Nested Dielectrics in Ray
//! Traced Images", JGT 2002): the *innermost* volume is the one of highest priority, the most
//! recently entered among equals. A boundary whose priority is lower than the innermost
//! volume's is a *false boundary*: the ray crosses it without refraction or shading (the stack
//! still records the crossing so that leaving later is matched).

use smallvec::SmallVec;
use std::sync::Arc;

/// One volume a ray is inside: the interior of `shape`, owned by `material`'s factory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VolumeEntry {
    /// Index of the material (Bxdf factory) whose `begin_interior` creates this volume's
    /// integrator.
    pub material: u32,
    /// Index of the shape whose closed surface bounds the volume.
    pub shape: u32,
    /// Priority of the material; higher wins where volumes overlap.
    pub priority: i32,
}

/// What happened to a stack when a ray crossed a boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StackEvent {
    /// The ray entered the interior of the crossed shape.
    Entered,
    /// The ray left the interior of the crossed shape.
    Exited,
    /// The ray crossed a back face of a shape it was not inside: the boundary is not closed,
    /// or the ray started inside without the renderer knowing. Nothing was removed.
    UnmatchedExit,
    /// The ray entered the interior of a shape it was already inside (a front face crossed
    /// twice without a back face between): the boundary is not closed, its normals are
    /// inconsistent, or an exit was missed. The entry was recorded again.
    EnteredAgain,
}

/// The entries of a stack of two or more volumes, shared between the stacks that hold them.
type Entries = SmallVec<[VolumeEntry; 4]>;

/// A stack's storage, by depth (the variant is always the one of the stack's length).
#[derive(Clone, Default)]
enum Repr {
    /// In no volume.
    #[default]
    Empty,
    /// In one volume (inline: no reference count, no allocation).
    One(VolumeEntry),
    /// In two or more volumes: shared with the stack's copies (`Arc`, so a copy is a
    /// reference count increment) and copied only when changed (`Arc::make_mut`).
    Many(Arc<Entries>),
}

/// The volumes a ray is inside, in the order they were entered.
///
/// Every ray row carries a stack, every bounce copies it, and the ray tables grow and
/// shrink every batch, so the empty stack (nearly every ray of most scenes) must be cheap to
/// create, copy and drop: the stack is 16 bytes (an inline `SmallVec` was 64 bytes to write
/// per row created and a capacity to load per row dropped). One volume, the common case of
/// scenes with glass, is stored inline too; deeper stacks share their entries between
/// copies.
#[derive(Clone, Default)]
pub struct VolumeStack {
    repr: Repr,
}

impl PartialEq for VolumeStack {
    /// Equal entries (not the same storage).
    #[inline]
    fn eq(&self, other: &Self) -> bool {
        match (&self.repr, &other.repr) {
            (Repr::Empty, Repr::Empty) => true,
            (Repr::One(a), Repr::One(b)) => a == b,
            // The variant is the one of the length: different variants, different lengths.
            (Repr::Many(a), Repr::Many(b)) => a[..] == b[..],
            _ => false,
        }
    }
}

impl Eq for VolumeStack {}

impl std::hash::Hash for VolumeStack {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.entries().hash(state);
    }
}

impl std::fmt::Debug for VolumeStack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VolumeStack")
            .field("entries", &self.entries())
            .finish()
    }
}

impl VolumeStack {
    /// An empty stack (the ray is in no volume: vacuum).
    pub fn new() -> Self {
        Self::default()
    }

    /// True when the ray is in no volume.
    #[inline]
    pub fn is_empty(&self) -> bool {
        matches!(self.repr, Repr::Empty)
    }

    /// Number of volumes the ray is inside.
    pub fn len(&self) -> usize {
        self.entries().len()
    }

    /// The volumes, oldest first.
    #[inline]
    pub fn entries(&self) -> &[VolumeEntry] {
        match &self.repr {
            Repr::Empty => &[],
            Repr::One(e) => std::slice::from_ref(e),
            Repr::Many(e) => e,
        }
    }

    /// The innermost volume: highest priority, most recently entered among equals.
    #[inline]
    pub fn innermost(&self) -> Option<VolumeEntry> {
        match &self.repr {
            Repr::Empty => None,
            Repr::One(e) => Some(*e),
            Repr::Many(entries) => self.innermost_index().map(|i| entries[i]),
        }
    }

    /// True when a boundary of `priority` is a false boundary for a ray with this stack: the
    /// ray is inside a volume of strictly higher priority, so the boundary neither refracts nor
    /// shades. A boundary of a shape the ray is inside is judged against the *other* volumes,
    /// so that leaving the innermost volume is never false.
    #[inline]
    pub fn is_false_boundary(&self, shape: u32, priority: i32) -> bool {
        let judged = |e: &VolumeEntry| e.shape != shape && e.priority > priority;
        match &self.repr {
            Repr::Empty => false,
            Repr::One(e) => judged(e),
            Repr::Many(entries) => entries.iter().any(judged),
        }
    }

    /// True when the ray is inside the interior of `shape`.
    pub fn contains_shape(&self, shape: u32) -> bool {
        self.entries().iter().any(|e| e.shape == shape)
    }

    /// Records that the ray entered `entry`'s volume.
    #[inline]
    pub fn enter(&mut self, entry: VolumeEntry) -> StackEvent {
        // Entering the first volume, the common case, inline; deeper stacks out of line.
        if let Repr::Empty = self.repr {
            self.repr = Repr::One(entry);
            return StackEvent::Entered;
        }
        self.enter_nested(entry)
    }

    /// [`enter`](Self::enter) on a stack that holds a volume already.
    fn enter_nested(&mut self, entry: VolumeEntry) -> StackEvent {
        let again = self.contains_shape(entry.shape);
        match &mut self.repr {
            Repr::Empty => self.repr = Repr::One(entry),
            Repr::One(first) => {
                self.repr = Repr::Many(Arc::new(SmallVec::from_slice(&[*first, entry])));
            }
            // A private copy of the entries first when they are shared.
            Repr::Many(shared) => Arc::make_mut(shared).push(entry),
        }
        if again {
            StackEvent::EnteredAgain
        } else {
            StackEvent::Entered
        }
    }

    /// Records that the ray left the interior of `shape` (the most recent entry of it).
    #[inline]
    pub fn exit(&mut self, shape: u32) -> StackEvent {
        // Leaving the only volume, the common case, inline; the rest out of line.
        if let Repr::One(e) = &self.repr {
            if e.shape == shape {
                self.repr = Repr::Empty;
                return StackEvent::Exited;
            }
        }
        self.exit_general(shape)
    }

    /// [`exit`](Self::exit) other than from a one-volume stack of `shape`.
    fn exit_general(&mut self, shape: u32) -> StackEvent {
        let Some(i) = self.entries().iter().rposition(|e| e.shape == shape) else {
            return StackEvent::UnmatchedExit;
        };
        match &mut self.repr {
            // Found, so not empty.
            Repr::Empty => {}
            Repr::One(_) => self.repr = Repr::Empty,
            Repr::Many(shared) if shared.len() == 2 => self.repr = Repr::One(shared[1 - i]),
            Repr::Many(shared) => {
                Arc::make_mut(shared).remove(i);
            }
        }
        StackEvent::Exited
    }

    /// Applies a transmit crossing of `entry.shape`'s surface: entering on a front face,
    /// leaving on a back face.
    #[inline]
    pub fn cross(&mut self, entry: VolumeEntry, front_face: bool) -> StackEvent {
        if front_face {
            self.enter(entry)
        } else {
            self.exit(entry.shape)
        }
    }

    /// Index (into [`entries`](Self::entries)) of the innermost volume.
    pub fn innermost_index(&self) -> Option<usize> {
        let entries = self.entries();
        let mut best: Option<usize> = None;
        for (i, e) in entries.iter().enumerate() {
            // `>=` so that a later entry of equal priority wins.
            if best.is_none_or(|b| e.priority >= entries[b].priority) {
                best = Some(i);
            }
        }
        best
    }

    /// The volumes other than the innermost, oldest first (RIS `GetOverlappingVolumes`).
    pub fn overlapping(&self) -> impl Iterator<Item = VolumeEntry> + '_ {
        let inner = self.innermost_index();
        self.entries()
            .iter()
            .enumerate()
            .filter(move |(i, _)| Some(*i) != inner)
            .map(|(_, e)| *e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(material: u32, shape: u32, priority: i32) -> VolumeEntry {
        VolumeEntry {
            material,
            shape,
            priority,
        }
    }

    #[test]
    fn copies_are_independent_values() {
        // Copies share entries until one changes: the other must not see the change.
        let mut a = VolumeStack::new();
        a.enter(e(1, 1, 0));
        let mut b = a.clone();
        b.enter(e(2, 2, 3));
        assert_eq!(a.entries(), &[e(1, 1, 0)]);
        assert_eq!(b.entries(), &[e(1, 1, 0), e(2, 2, 3)]);
        let c = b.clone();
        assert_eq!(b.exit(1), StackEvent::Exited);
        assert_eq!(b.entries(), &[e(2, 2, 3)]);
        assert_eq!(c.len(), 2);
        assert_eq!(a.len(), 1);
    }

    #[test]
    fn emptied_stack_equals_a_new_one() {
        // Equality is by entries, whatever the stacks' history (the partition system keys
        // bundles by equal stacks).
        let mut s = VolumeStack::new();
        s.enter(e(1, 1, 0));
        assert_ne!(s, VolumeStack::new());
        s.exit(1);
        assert!(s.is_empty());
        assert_eq!(s.len(), 0);
        assert_eq!(s, VolumeStack::new());
        assert_eq!(s.entries(), &[] as &[VolumeEntry]);
        assert_eq!(s.innermost(), None);
        // Small enough that a column of empty stacks is cheap to fill.
        assert!(std::mem::size_of::<VolumeStack>() <= 16);
    }

    #[test]
    fn equality_is_by_entries_at_every_depth() {
        // Reached through different histories (a `Many` left down to one entry, entries
        // entered in another order) the stacks compare by their entries alone.
        let mut a = VolumeStack::new();
        a.enter(e(1, 1, 0));
        a.enter(e(2, 2, 0));
        let mut one = a.clone();
        one.exit(1);
        let mut fresh = VolumeStack::new();
        fresh.enter(e(2, 2, 0));
        assert_eq!(one, fresh);
        let mut b = VolumeStack::new();
        b.enter(e(1, 1, 0));
        b.enter(e(2, 2, 0));
        assert_eq!(a, b);
        let mut swapped = VolumeStack::new();
        swapped.enter(e(2, 2, 0));
        swapped.enter(e(1, 1, 0));
        assert_ne!(a, swapped);
        assert_ne!(a, one);
        assert_ne!(one, VolumeStack::new());
        b.enter(e(3, 3, 0));
        assert_ne!(a, b);
        // The innermost of each form matches the general search.
        for s in [&a, &one, &fresh, &b, &swapped, &VolumeStack::new()] {
            assert_eq!(s.innermost(), s.innermost_index().map(|i| s.entries()[i]));
        }
    }

    #[test]
    fn cross_equals_enter_and_exit() {
        // The inline fast paths of `enter` / `exit` (through `cross`) against their general
        // forms, from every form of stack.
        let starts = {
            let mut one = VolumeStack::new();
            one.enter(e(1, 1, 0));
            let mut two = one.clone();
            two.enter(e(2, 2, 1));
            [VolumeStack::new(), one, two]
        };
        for start in &starts {
            for entry in [e(1, 1, 0), e(2, 2, 1), e(3, 3, 5)] {
                for front in [true, false] {
                    let (mut a, mut b) = (start.clone(), start.clone());
                    let event = a.cross(entry, front);
                    let want = if front {
                        b.enter_nested(entry)
                    } else {
                        b.exit_general(entry.shape)
                    };
                    assert_eq!(event, want, "{start:?} {entry:?} {front}");
                    assert_eq!(a, b, "{start:?} {entry:?} {front}");
                }
            }
        }
    }

    #[test]
    fn deep_nesting_is_unbounded() {
        let mut s = VolumeStack::new();
        for i in 0..9 {
            s.enter(e(i, i, i as i32));
        }
        let copy = s.clone();
        for i in (0..9).rev() {
            assert_eq!(s.innermost(), Some(e(i, i, i as i32)));
            assert_eq!(s.exit(i), StackEvent::Exited);
        }
        assert!(s.is_empty());
        assert_eq!(copy.len(), 9);
    }

    #[test]
    fn enter_then_exit_returns_to_empty() {
        let mut s = VolumeStack::new();
        assert_eq!(s.cross(e(1, 7, 0), true), StackEvent::Entered);
        assert_eq!(s.innermost(), Some(e(1, 7, 0)));
        assert_eq!(s.cross(e(1, 7, 0), false), StackEvent::Exited);
        assert!(s.is_empty());
    }

    #[test]
    fn exit_without_enter_is_unmatched_and_harmless() {
        let mut s = VolumeStack::new();
        s.enter(e(1, 1, 0));
        assert_eq!(s.exit(9), StackEvent::UnmatchedExit);
        // Entering a shape the ray is already inside is reported (and recorded again).
        let mut twice = VolumeStack::new();
        assert_eq!(twice.enter(e(3, 3, 0)), StackEvent::Entered);
        assert_eq!(twice.enter(e(3, 3, 0)), StackEvent::EnteredAgain);
        assert_eq!(twice.len(), 2);
        assert_eq!(s.len(), 1);
    }

    #[test]
    fn innermost_is_highest_priority_then_latest() {
        let mut s = VolumeStack::new();
        s.enter(e(1, 1, 5)); // glass, high priority
        s.enter(e(2, 2, 1)); // liquid, lower priority, entered later
        assert_eq!(s.innermost().map(|v| v.shape), Some(1));
        s.enter(e(3, 3, 5)); // equal priority, later: wins
        assert_eq!(s.innermost().map(|v| v.shape), Some(3));
    }

    #[test]
    fn lower_priority_boundary_inside_higher_volume_is_false() {
        let mut s = VolumeStack::new();
        s.enter(e(1, 1, 2)); // inside glass (priority 2)
        assert!(s.is_false_boundary(2, 1)); // liquid surface (priority 1) inside the glass
        assert!(!s.is_false_boundary(1, 2)); // the glass's own boundary: leaving is real
        assert!(!s.is_false_boundary(3, 2)); // equal priority: real boundary
    }

    #[test]
    fn overlapping_excludes_exactly_the_innermost() {
        let mut s = VolumeStack::new();
        s.enter(e(1, 1, 0));
        s.enter(e(2, 2, 0));
        s.enter(e(3, 3, 0));
        let o: Vec<u32> = s.overlapping().map(|v| v.shape).collect();
        assert_eq!(o, vec![1, 2]);
    }

    #[test]
    fn coincident_surfaces_enter_and_leave_in_any_order() {
        // Two shapes sharing a boundary: the ray enters both at one point and can leave them
        // in either order without corrupting the stack.
        let mut s = VolumeStack::new();
        s.cross(e(1, 1, 0), true);
        s.cross(e(2, 2, 0), true);
        s.cross(e(1, 1, 0), false);
        assert_eq!(s.entries(), &[e(2, 2, 0)]);
        s.cross(e(2, 2, 0), false);
        assert!(s.is_empty());
    }
    #[test]
    fn coincident_surfaces_left_in_reverse_order() {
        // Same shared boundary, left in the opposite order (last in, first out): the innermost
        // is always the remaining most recent entry.
        let mut s = VolumeStack::new();
        s.cross(e(1, 1, 0), true);
        s.cross(e(2, 2, 0), true);
        assert_eq!(s.innermost(), Some(e(2, 2, 0)));
        assert_eq!(s.cross(e(2, 2, 0), false), StackEvent::Exited);
        assert_eq!(s.innermost(), Some(e(1, 1, 0)));
        assert_eq!(s.cross(e(1, 1, 0), false), StackEvent::Exited);
        assert!(s.is_empty());
    }

    #[test]
    fn coincident_surfaces_left_in_entry_order_keep_the_other_innermost() {
        // Entered 1 then 2, left 1 first: 2 stays and is innermost; the overlap list is empty.
        let mut s = VolumeStack::new();
        s.cross(e(1, 1, 0), true);
        s.cross(e(2, 2, 0), true);
        assert_eq!(s.overlapping().count(), 1);
        s.cross(e(1, 1, 0), false);
        assert_eq!(s.innermost(), Some(e(2, 2, 0)));
        assert_eq!(s.overlapping().count(), 0);
    }

    #[test]
    fn rays_starting_on_a_boundary_take_the_side_they_leave_to() {
        // A ray spawned on the surface of shape 4 (a refraction or a shadow ray towards the
        // inside) gets the stack *after* the crossing: the shape is then its innermost volume
        // and the boundary it starts on is a real boundary for it (leaving again is matched).
        let glass = e(3, 4, 1);
        let outside = VolumeStack::new();
        let mut inward = outside.clone();
        assert_eq!(inward.cross(glass, true), StackEvent::Entered);
        assert_eq!(inward.innermost(), Some(glass));
        assert!(!inward.is_false_boundary(4, 1));
        assert!(inward.contains_shape(4));
        // The reflected ray (no transmit bit) keeps the outside stack.
        assert!(outside.is_empty());
        // From inside, a ray leaving through the boundary it starts on returns to vacuum,
        // while the stack of the reflected ray still holds the glass.
        let mut outward = inward.clone();
        assert_eq!(outward.cross(glass, false), StackEvent::Exited);
        assert!(outward.is_empty());
        assert_eq!(inward.innermost(), Some(glass));
        // A second, spurious back-face crossing of the same boundary (a self-intersection the
        // ray offset should have avoided) cannot corrupt the stack: it is an unmatched exit.
        assert_eq!(outward.cross(glass, false), StackEvent::UnmatchedExit);
        assert!(outward.is_empty());
    }

    #[test]
    fn liquid_in_glass_walk() {
        // A glass (priority 2) with a liquid (priority 1) whose surface lies slightly inside
        // the glass wall (the liquid overlaps the wall). A ray from the air, straight through.
        let glass = e(1, 10, 2);
        let liquid = e(2, 20, 1);
        let mut s = VolumeStack::new();
        // Outer glass wall: a real boundary (nothing of higher priority around).
        assert!(!s.is_false_boundary(10, 2));
        s.cross(glass, true);
        // The liquid's surface, inside the wall: a false boundary, still recorded.
        assert!(s.is_false_boundary(20, 1));
        s.cross(liquid, true);
        assert_eq!(s.innermost(), Some(glass), "the glass wins inside the wall");
        assert_eq!(s.overlapping().collect::<Vec<_>>(), vec![liquid]);
        // Inner glass wall: real (the glass's own boundary), leaving the glass into the liquid.
        assert!(!s.is_false_boundary(10, 2));
        s.cross(glass, false);
        assert_eq!(s.innermost(), Some(liquid));
        // Across the liquid, into the glass wall on the far side: real for the glass.
        assert!(!s.is_false_boundary(10, 2));
        s.cross(glass, true);
        assert_eq!(s.innermost(), Some(glass));
        // The liquid's far surface inside the wall: false, leaves the liquid.
        assert!(s.is_false_boundary(20, 1));
        assert_eq!(s.cross(liquid, false), StackEvent::Exited);
        assert_eq!(s.entries(), &[glass]);
        // Out of the glass into the air.
        assert!(!s.is_false_boundary(10, 2));
        s.cross(glass, false);
        assert!(s.is_empty());
    }
}
