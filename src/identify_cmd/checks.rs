//! A template's checks against the measures: defining checks (the property that makes the
//! template what it is: a press does not travel, a slide travels while in contact, a touch stops
//! at first contact; all must hold for the template to fit) and supporting checks (what else it
//! expects; they order the templates that fit).

use serde::Serialize;

use super::measure::{Measures, STILL_M};
use super::profile::{Contacts, ForceShape, InContact, Profile, Surface};

/// Travel in contact beyond this is sliding \[m\].
const SLIDING_M: f64 = 0.03;
/// A contact force that turns more than this follows a curved surface \[°\].
const CURVED_DEG: f64 = 15.0;
/// A contact that turns less than this is on a plane \[°\].
const FLAT_DEG: f64 = 12.0;
/// A touch lasts less than this \[s\].
const TOUCH_S: f64 = 0.6;
/// A tap lasts less than this, a hold at least this \[s\].
const TAP_S: f64 = 1.5;
/// A hold holds its level over at least this share of the contact.
const HOLD_SHARE: f64 = 0.65;
/// A slide that ends in a press ends at least this many times its sliding force.
const FIRM_END_RATIO: f64 = 1.8;

/// One check of a template against the measures.
#[derive(Debug, Clone, Serialize)]
pub struct Evidence {
    /// What is checked, with the value found.
    pub check: String,
    /// Whether it holds.
    pub passed: bool,
    /// A defining check: the template does not fit when it fails.
    pub defining: bool,
}

fn defining(check: String, passed: bool) -> Evidence {
    Evidence {
        check,
        passed,
        defining: true,
    }
}

fn supporting(check: String, passed: bool) -> Evidence {
    Evidence {
        check,
        passed,
        defining: false,
    }
}

/// What a template of `profile` expects of the measures, defining checks first.
pub(super) fn checks(profile: &Profile, m: &Measures) -> Vec<Evidence> {
    let mut out = Vec::new();
    let cm = m.travel_m * 100.0;
    match profile.contacts {
        Contacts::Exactly(want) => out.push(defining(
            format!("{} contact phase(s), expects {want}", m.phases),
            m.phases == want,
        )),
        Contacts::One => out.push(supporting(
            format!("{} contact phase(s), expects 1", m.phases),
            m.phases == 1,
        )),
        Contacts::AtLeastOne => out.push(supporting(
            format!("{} contact phase(s), expects one or more", m.phases),
            m.phases >= 1,
        )),
    }
    let several = matches!(profile.contacts, Contacts::Exactly(n) if n >= 2);
    match profile.in_contact {
        InContact::Still if several => {
            let put = m.per_phase.iter().all(|[_, travel]| *travel < STILL_M);
            let most = m.per_phase.iter().map(|[_, t]| *t).fold(0.0, f64::max) * 100.0;
            out.push(defining(
                format!("each contact stays put: travel up to {most:.1} cm, expects under 1 cm"),
                put && !m.per_phase.is_empty(),
            ));
            let short = m.per_phase.iter().all(|[d, _]| *d < TAP_S);
            out.push(supporting(
                format!("taps under {TAP_S} s each: {short}"),
                short && !m.per_phase.is_empty(),
            ));
            out.push(supporting(
                format!("taps {:.1} cm apart, expects 1 cm or more", m.apart_m * 100.0),
                m.apart_m >= STILL_M,
            ));
        }
        InContact::Still => out.push(defining(
            format!("travel in contact {cm:.1} cm, expects under 1 cm (stays put)"),
            m.travel_m < STILL_M,
        )),
        InContact::Slides => {
            out.push(defining(
                format!("travel in contact {cm:.1} cm, expects 3 cm or more (slides)"),
                m.travel_m >= SLIDING_M,
            ));
            out.push(defining(
                format!("{} stroke reversal(s), expects none (one way)", m.reversals),
                m.reversals == 0,
            ));
        }
        InContact::Strokes => {
            out.push(defining(
                format!("travel in contact {cm:.1} cm, expects 3 cm or more (slides)"),
                m.travel_m >= SLIDING_M,
            ));
            out.push(defining(
                format!("{} stroke reversal(s), expects 1 or more (back and forth)", m.reversals),
                m.reversals >= 1,
            ));
            out.push(supporting(
                format!("{} stroke reversal(s), expects 2 or more", m.reversals),
                m.reversals >= 2,
            ));
        }
    }
    // A contact that lasts to the recording's end has no known length or shape.
    if !profile.ends_in_contact && !several {
        let hold = m.hold_share * 100.0;
        match profile.force {
            ForceShape::Any => {}
            ForceShape::Brief => out.push(defining(
                format!(
                    "contact {:.2} s, expects under {TOUCH_S} s (stops at first contact)",
                    m.duration_s
                ),
                m.duration_s < TOUCH_S,
            )),
            ForceShape::Profile => {
                out.push(defining(
                    format!("contact {:.2} s, expects {TOUCH_S} s or more", m.duration_s),
                    m.duration_s >= TOUCH_S,
                ));
                out.push(supporting(
                    format!("force at its level {hold:.0} % of the contact, expects a profile (under 65 %)"),
                    m.hold_share < HOLD_SHARE,
                ));
            }
            ForceShape::Hold => {
                out.push(defining(
                    format!("contact {:.2} s, expects {TAP_S} s or more", m.duration_s),
                    m.duration_s >= TAP_S,
                ));
                out.push(defining(
                    format!("force at its level {hold:.0} % of the contact, expects 65 % or more (holds)"),
                    m.hold_share >= HOLD_SHARE,
                ));
            }
        }
    }
    match profile.surface {
        Surface::Any => {}
        Surface::Flat => out.push(supporting(
            format!("force turns {:.0}°, expects under 12° (a plane)", m.turn_deg),
            m.turn_deg < FLAT_DEG,
        )),
        Surface::Curved => out.push(defining(
            format!("force turns {:.0}°, expects 15° or more (a curved surface)", m.turn_deg),
            m.turn_deg >= CURVED_DEG,
        )),
    }
    match profile.firm_end {
        None => {}
        Some(true) => out.push(defining(
            format!(
                "end force {:.1}× the sliding force, expects 1.8× or more (ends pressing)",
                m.end_ratio
            ),
            m.end_ratio >= FIRM_END_RATIO,
        )),
        Some(false) => out.push(supporting(
            format!("end force {:.1}× the sliding force, expects under 1.8×", m.end_ratio),
            m.end_ratio < FIRM_END_RATIO,
        )),
    }
    let away = if m.end_away_m.is_finite() {
        format!(", {:.1} cm from the contact", m.end_away_m * 100.0)
    } else {
        String::new()
    };
    let ends = if m.ends_in_contact { "" } else { "not " };
    if profile.ends_in_contact {
        out.push(defining(
            format!("ends {ends}in contact{away}, expects the recording to end in contact"),
            m.ends_in_contact,
        ));
    } else {
        out.push(supporting(
            format!("ends {ends}in contact{away}, expects a retreat"),
            !m.ends_in_contact,
        ));
    }
    out
}

/// Whether all defining checks hold, and the score: above 0.5 for a template that fits (0.5 plus
/// half the share of supporting checks that hold), under 0.5 for one that does not (mostly the
/// share of defining checks that hold), so a template that fits always ranks above one that
/// does not, however many supporting checks the other passes.
pub(super) fn score(evidence: &[Evidence]) -> (bool, f64) {
    let share = |defining: bool| {
        let (all, passed) = evidence
            .iter()
            .filter(|e| e.defining == defining)
            .fold((0usize, 0usize), |(all, passed), e| {
                (all + 1, passed + usize::from(e.passed))
            });
        if all == 0 {
            1.0
        } else {
            passed as f64 / all as f64
        }
    };
    let (defining, supporting) = (share(true), share(false));
    if defining >= 1.0 {
        (true, 0.5 + 0.5 * supporting)
    } else {
        (false, 0.5 * (0.8 * defining + 0.2 * supporting) * 0.99)
    }
}
