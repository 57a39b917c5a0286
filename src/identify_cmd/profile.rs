//! What a template expects of a demonstration, as a few structural features ([`Profile`]): how
//! many contacts, whether the tool stays put, slides or strokes back and forth while in contact,
//! the shape of the force, the surface, and how the skill ends. The standard templates' profiles
//! are written out ([`Profile::standard`]); a user's template's is derived from its IR
//! ([`Profile::from_skill`]) the same way, so a template that is structurally a slide is judged
//! as the slide is (tests/identify_templates.rs checks that the derivation gives the written
//! profiles for every shipped template).

use serde::Serialize;
use skill_ir::{
    ConstraintModel, ForceSource, FrameRef, FrameSource, Guard, Outcome, Point, Segmentation, Skill, StateKind,
    TransitionAction,
};

/// How many contact phases a template expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Contacts {
    /// One contact (a supporting check: a real recording may show a stray phase).
    One,
    /// Exactly this many (defining: a double tap is two contacts).
    Exactly(usize),
    /// One or more (a wipe of several passes).
    AtLeastOne,
}

/// What the tool does while in contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InContact {
    /// It stays put (touch, press, hold, a guarded move's rest, taps).
    Still,
    /// It travels one way (slide, contour).
    Slides,
    /// It travels back and forth (wipe: a motion learned as strokes).
    Strokes,
}

/// The shape of the contact force of a template whose tool stays put.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceShape {
    /// Not judged (the sliding templates, several taps).
    Any,
    /// A brief contact: the force at one point (touch: it stops at first contact).
    Brief,
    /// A force profile over a contact of some length (press).
    Profile,
    /// A force held at one level (press and hold).
    Hold,
}

/// The surface a sliding template follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Surface {
    /// Not judged.
    Any,
    /// A plane (a supporting check).
    Flat,
    /// A curved surface: the contact normal turns (defining: a contour).
    Curved,
}

/// A template's structural features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Profile {
    /// How many contacts.
    pub contacts: Contacts,
    /// The tool while in contact.
    pub in_contact: InContact,
    /// The force's shape while the tool stays put.
    pub force: ForceShape,
    /// The surface while it slides.
    pub surface: Surface,
    /// A slide that ends pressing harder (`Some(true)`: defining), or that must not
    /// (`Some(false)`: supporting); `None`: not judged.
    pub firm_end: Option<bool>,
    /// The skill ends in contact (defining: a guarded move) instead of retreating (supporting).
    pub ends_in_contact: bool,
}

impl Profile {
    /// The profile of a standard template, by name.
    pub fn standard(name: &str) -> Option<Profile> {
        let still = |force, ends_in_contact| Profile {
            contacts: Contacts::One,
            in_contact: InContact::Still,
            force,
            surface: Surface::Any,
            firm_end: None,
            ends_in_contact,
        };
        let sliding = |surface, firm_end| Profile {
            contacts: Contacts::One,
            in_contact: InContact::Slides,
            force: ForceShape::Any,
            surface,
            firm_end: Some(firm_end),
            ends_in_contact: false,
        };
        Some(match name {
            "touch" => still(ForceShape::Brief, false),
            "press" => still(ForceShape::Profile, false),
            "press_hold" => still(ForceShape::Hold, false),
            "guarded_move" => still(ForceShape::Hold, true),
            "double_tap" => Profile {
                contacts: Contacts::Exactly(2),
                force: ForceShape::Any,
                ..still(ForceShape::Any, false)
            },
            "slide" => sliding(Surface::Flat, false),
            "slide_then_press" => sliding(Surface::Flat, true),
            "contour" => Profile {
                firm_end: None,
                ..sliding(Surface::Curved, false)
            },
            "wipe" => Profile {
                contacts: Contacts::AtLeastOne,
                in_contact: InContact::Strokes,
                firm_end: None,
                ..sliding(Surface::Flat, false)
            },
            _ => return None,
        })
    }

    /// The profile a template's IR shows: the segments it learns a force on or runs a
    /// force-controlled motion on are its contacts (consecutive ones one contact); a motion
    /// learned on a contact segment slides (strokes: back and forth); the force learned on a
    /// still contact says its shape (at a point: brief; a profile; a constant: held); the frame
    /// of a sliding contact its surface (a plane fitted: flat; the force's direction at every
    /// sample: curved); a contact segment without motion after the sliding one is a firm end;
    /// and a success reached from a force-controlled state, or on a force guard, ends in contact.
    pub fn from_skill(skill: &Skill) -> Profile {
        let plan = &skill.learn;
        let segments = plan.segments.max(1) as usize;
        let mut contact = vec![false; segments];
        let mut brief = matches!(plan.segmentation, Segmentation::MaxForce);
        let mark = |index: usize, contact: &mut [bool]| {
            if index < contact.len() {
                contact[index] = true;
            }
        };
        for force in &plan.forces {
            match &force.source {
                ForceSource::Constant { segment, .. }
                | ForceSource::Dmp { segment, .. }
                | ForceSource::Magnitude { segment, .. } => mark(segment.index(), &mut contact),
                ForceSource::At { point, .. } => {
                    brief = true;
                    match point {
                        // The force where a segment ends is where the next one's contact begins.
                        Point::End(segment) if !matches!(plan.segmentation, Segmentation::MaxForce) => {
                            mark(segment.index() + 1, &mut contact)
                        }
                        Point::Start(segment) | Point::PeakForceIn(segment) => mark(segment.index(), &mut contact),
                        _ => {}
                    }
                }
                ForceSource::Literal { .. } | ForceSource::Tracked => {}
            }
        }
        let force_controlled: Vec<bool> = skill
            .states
            .iter()
            .map(|state| match &state.kind {
                StateKind::Active(active) => active.position_controlled.iter().any(|p| !p),
                StateKind::Terminal { .. } => false,
            })
            .collect();
        let motion_segment = |motion: skill_ir::MotionId| plan.motions.get(motion.index()).map(|m| m.segment.index());
        for (state, forced) in skill.states.iter().zip(&force_controlled) {
            if let (StateKind::Active(active), true) = (&state.kind, forced) {
                if let Some(segment) = active.motion.and_then(motion_segment) {
                    mark(segment, &mut contact);
                }
            }
        }
        // Contacts: runs of consecutive contact segments.
        let runs = contact
            .iter()
            .enumerate()
            .filter(|(i, c)| **c && (*i == 0 || !contact[i - 1]))
            .count();
        let moving: Vec<(usize, bool)> = plan
            .motions
            .iter()
            .filter(|m| contact.get(m.segment.index()).copied().unwrap_or(false))
            .map(|m| (m.segment.index(), m.strokes.is_some()))
            .collect();
        let in_contact = if moving.iter().any(|(_, strokes)| *strokes) {
            InContact::Strokes
        } else if moving.is_empty() {
            InContact::Still
        } else {
            InContact::Slides
        };
        let contacts = match (runs, in_contact) {
            (n, _) if n >= 2 => Contacts::Exactly(n),
            (_, InContact::Strokes) => Contacts::AtLeastOne,
            _ => Contacts::One,
        };
        let ends_in_contact = ends_in_contact(skill, &force_controlled);
        let force = if in_contact != InContact::Still || runs >= 2 {
            ForceShape::Any
        } else if brief {
            ForceShape::Brief
        } else if plan.forces.iter().any(|f| {
            matches!(
                f.source,
                ForceSource::Constant { .. } | ForceSource::Literal { .. } | ForceSource::Tracked
            )
        }) {
            ForceShape::Hold
        } else {
            ForceShape::Profile
        };
        let (surface, firm_end) = match in_contact {
            InContact::Still => (Surface::Any, None),
            _ => {
                let last_moving = moving.iter().map(|(s, _)| *s).max().unwrap_or(0);
                let firm = contact
                    .iter()
                    .enumerate()
                    .skip(last_moving + 1)
                    .take_while(|(_, c)| **c)
                    .count()
                    > 0;
                let surface = sliding_surface(skill, last_moving);
                let firm_end = match (in_contact, surface) {
                    (InContact::Slides, Surface::Curved) if !firm => None,
                    (InContact::Strokes, _) if !firm => None,
                    _ => Some(firm),
                };
                (surface, firm_end)
            }
        };
        Profile {
            contacts,
            in_contact,
            force,
            surface,
            firm_end,
            ends_in_contact,
        }
    }
}

/// Whether a success is reached from a force-controlled state or on a force guard.
fn ends_in_contact(skill: &Skill, force_controlled: &[bool]) -> bool {
    let success = |id: skill_ir::StateId| {
        skill.states.get(id.index()).is_some_and(|s| {
            matches!(
                s.kind,
                StateKind::Terminal {
                    outcome: Outcome::Success,
                    ..
                }
            )
        })
    };
    skill.transitions.iter().any(|t| {
        let target = match &t.action {
            TransitionAction::Goto { target } => *target,
            TransitionAction::Extend { then, .. } => *then,
        };
        success(target) && (force_controlled.get(t.from.index()).copied().unwrap_or(false) || on_force(&t.guard))
    })
}

/// A guard that fires on a contact force.
fn on_force(guard: &Guard) -> bool {
    match guard {
        Guard::And { all } => all.iter().any(on_force),
        Guard::Or { any } => any.iter().any(on_force),
        Guard::Held { guard, .. } => on_force(guard),
        Guard::Force { .. } | Guard::ForceMagnitude { .. } => true,
        _ => false,
    }
}

/// The surface of the frame the sliding segment's force-controlled state works in.
fn sliding_surface(skill: &Skill, segment: usize) -> Surface {
    let plan = &skill.learn;
    let frame = skill.states.iter().find_map(|state| match &state.kind {
        StateKind::Active(active)
            if active.position_controlled.iter().any(|p| !p)
                && active
                    .motion
                    .and_then(|m| plan.motions.get(m.index()))
                    .is_some_and(|m| m.segment.index() == segment) =>
        {
            match active.frame {
                FrameRef::Learned(id) => plan.frames.get(id.index()),
                _ => None,
            }
        }
        _ => None,
    });
    match frame.map(|f| &f.source) {
        Some(FrameSource::ForceAlignedSamples { .. }) => Surface::Curved,
        Some(FrameSource::Constraint { candidates, .. })
            if !candidates.is_empty()
                && candidates
                    .iter()
                    .all(|c| matches!(c, ConstraintModel::Planar | ConstraintModel::PointOnPlane)) =>
        {
            Surface::Flat
        }
        _ => Surface::Any,
    }
}
