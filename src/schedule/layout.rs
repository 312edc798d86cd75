//! The dam as the schedule sees it, and the checks of a schedule against it.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use crate::vocab::ZoneId;

use super::check::lifts_label;
use super::error::ScheduleError;
use super::{Pour, Schedules, COOLING_CSV, GROUTING_CSV, JOINT_METERS_CSV, POURS_CSV};

/// The blocks, lifts and grouting zones of a dam, without geometry. Built by
/// the caller from the mesh; this module does not depend on `mesh`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DamLayout {
    /// `(block, n_lifts)`: every block of the dam and its number of lifts.
    pub blocks: Vec<(u32, u32)>,
    /// Every grouting zone of every joint.
    pub zones: Vec<ZoneExtent>,
}

/// One grouting zone of one joint: the lifts of the two blocks it spans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct ZoneExtent {
    pub joint: u32,
    pub zone: u32,
    /// `(block, first lift, last lift)` on one side (normally block `joint`).
    pub lifts_a: (u32, u32, u32),
    /// `(block, first lift, last lift)` on the other side (normally `joint + 1`).
    pub lifts_b: (u32, u32, u32),
}

impl ZoneExtent {
    pub fn zone_id(&self) -> ZoneId {
        ZoneId::new(self.joint, self.zone)
    }

    /// Both sides: `[(block, first lift, last lift); 2]`.
    pub fn sides(&self) -> [(u32, u32, u32); 2] {
        [self.lifts_a, self.lifts_b]
    }
}

impl DamLayout {
    /// Number of lifts of `block`, or `None` for an unknown block.
    pub fn n_lifts(&self, block: u32) -> Option<u32> {
        self.blocks.iter().find(|b| b.0 == block).map(|b| b.1)
    }

    /// The extent of `zone` of `joint`.
    pub fn zone(&self, id: ZoneId) -> Option<&ZoneExtent> {
        self.zones.iter().find(|z| z.zone_id() == id)
    }

    /// Joints that have at least one zone, ascending.
    pub fn joints(&self) -> Vec<u32> {
        let set: BTreeSet<u32> = self.zones.iter().map(|z| z.joint).collect();
        set.into_iter().collect()
    }

    /// Zones of `joint`, ascending.
    pub fn zones_of(&self, joint: u32) -> Vec<u32> {
        let set: BTreeSet<u32> = self
            .zones
            .iter()
            .filter(|z| z.joint == joint)
            .map(|z| z.zone)
            .collect();
        set.into_iter().collect()
    }

    /// Consistency of the layout itself: numbers ≥ 1, no duplicate block or
    /// (joint, zone), zone sides on known blocks within their lifts.
    pub fn validate(&self) -> Result<(), ScheduleError> {
        let bad = |m: String| Err(ScheduleError::InvalidLayout(m));
        let mut blocks: HashMap<u32, u32> = HashMap::new();
        for &(block, n) in &self.blocks {
            if block == 0 || n == 0 {
                return bad(format!("block {block} with {n} lifts (both must be ≥ 1)"));
            }
            if blocks.insert(block, n).is_some() {
                return bad(format!("block {block} is listed twice"));
            }
        }
        let mut zones = BTreeSet::new();
        for z in &self.zones {
            if z.joint == 0 || z.zone == 0 {
                return bad(format!(
                    "joint {} zone {} (both must be ≥ 1)",
                    z.joint, z.zone
                ));
            }
            if !zones.insert((z.joint, z.zone)) {
                return bad(format!("joint {} zone {} is listed twice", z.joint, z.zone));
            }
            for (block, first, last) in z.sides() {
                let Some(&n) = blocks.get(&block) else {
                    return bad(format!(
                        "joint {} zone {} spans block {block}, which is not in the layout",
                        z.joint, z.zone
                    ));
                };
                if first == 0 || first > last || last > n {
                    return bad(format!(
                        "joint {} zone {} spans lifts {first}-{last} of block {block}, which has lifts 1-{n}",
                        z.joint, z.zone
                    ));
                }
            }
        }
        Ok(())
    }
}

/// "1-5, 7, 9-12" for a sorted list of numbers.
pub(crate) fn ranges(sorted: &[u32]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        if i == j {
            parts.push(sorted[i].to_string());
        } else {
            parts.push(format!("{}-{}", sorted[i], sorted[j]));
        }
        i = j + 1;
    }
    parts.join(", ")
}

/// "zone 3" or "zones 1-5, 7".
pub(crate) fn named(noun: &str, sorted: &[u32]) -> String {
    if sorted.len() == 1 {
        format!("{noun} {}", sorted[0])
    } else {
        format!("{noun}s {}", ranges(sorted))
    }
}

fn block_label(layout_blocks: &BTreeMap<u32, u32>) -> String {
    let list: Vec<u32> = layout_blocks.keys().copied().collect();
    if list.is_empty() {
        "the dam has no blocks".to_string()
    } else {
        named("block", &list)
    }
}

/// Checks that `block` exists and `lift_to` is not above its top.
/// `lift_col` is the 1-based column of `lift_to` (the block is column 1).
fn check_block_lifts(
    file: &str,
    line: usize,
    lift_col: usize,
    blocks: &BTreeMap<u32, u32>,
    block: u32,
    lift_from: u32,
    lift_to: u32,
) -> Result<(), ScheduleError> {
    let Some(&n) = blocks.get(&block) else {
        return Err(ScheduleError::layout(
            file,
            line,
            1,
            format!("block {block} is not in the dam ({})", block_label(blocks)),
        ));
    };
    if lift_to > n {
        let lifts = lifts_label(lift_from, lift_to);
        let message = if lift_from == lift_to {
            format!("block {block} {lifts} is above the top of the block (lift {n})")
        } else {
            format!(
                "block {block} {lifts}: lift {lift_to} is above the top of the block (lift {n})"
            )
        };
        return Err(ScheduleError::layout(file, line, lift_col, message));
    }
    Ok(())
}

/// Checks that `zone` of `joint` exists; the message names what does.
fn check_joint_zone(
    file: &str,
    line: usize,
    layout: &DamLayout,
    joints: &[u32],
    joint: u32,
    zone: u32,
) -> Result<(), ScheduleError> {
    if !joints.contains(&joint) {
        let known = if joints.is_empty() {
            "the dam has no joints".to_string()
        } else {
            named("joint", joints)
        };
        return Err(ScheduleError::layout(
            file,
            line,
            1,
            format!("joint {joint} does not exist ({known})"),
        ));
    }
    let zones = layout.zones_of(joint);
    if zones.contains(&zone) {
        return Ok(());
    }
    let list = named("zone", &zones);
    let (lo, hi) = (zones.first().copied(), zones.last().copied());
    let message = match (lo, hi) {
        (_, Some(hi)) if zone > hi => {
            format!("joint {joint} zone {zone} is above the dam (joint {joint} has {list})")
        }
        (Some(lo), _) if zone < lo => {
            format!("joint {joint} zone {zone} is below the foundation (joint {joint} has {list})")
        }
        _ => format!("joint {joint} has no zone {zone} (it has {list})"),
    };
    Err(ScheduleError::layout(file, line, 2, message))
}

/// Checks a schedule against the dam: unknown blocks, lifts above a block's
/// top, cooling of unknown lifts, grouting of joints or zones that do not
/// exist, grouting planned before its zone exists (every lift of both blocks
/// spanning the zone must be poured strictly before the planned date), and
/// joint meters on unknown joints or zones. Rows are checked file by file
/// (pours, cooling, grouting, joint meters) in file order; the first problem
/// is returned. Assumes `s` passed [`super::load`] (or [`super::validate`]).
pub fn check_against(s: &Schedules, layout: &DamLayout) -> Result<(), ScheduleError> {
    layout.validate()?;
    let blocks: BTreeMap<u32, u32> = layout.blocks.iter().copied().collect();
    for p in &s.pours {
        check_block_lifts(POURS_CSV, p.line, 2, &blocks, p.block, p.lift, p.lift)?;
    }
    for c in &s.cooling {
        check_block_lifts(
            COOLING_CSV,
            c.line,
            3,
            &blocks,
            c.block,
            c.lift_from,
            c.lift_to,
        )?;
    }
    let joints = layout.joints();
    let pours: HashMap<(u32, u32), &Pour> =
        s.pours.iter().map(|p| ((p.block, p.lift), p)).collect();
    for g in &s.grouting {
        check_joint_zone(GROUTING_CSV, g.line, layout, &joints, g.joint, g.zone)?;
        let Some(z) = layout.zone(g.zone_id()) else {
            continue; // unreachable after check_joint_zone
        };
        let what = format!(
            "joint {} zone {} planned {}, before the zone exists",
            g.joint, g.zone, g.planned
        );
        // The latest pour among the zone's lifts (or the first missing lift).
        let mut latest: Option<&Pour> = None;
        for (block, first, last) in z.sides() {
            for lift in first..=last {
                match pours.get(&(block, lift)) {
                    None => {
                        return Err(ScheduleError::layout(
                            GROUTING_CSV,
                            g.line,
                            3,
                            format!("{what}: block {block} lift {lift} is not in {POURS_CSV}"),
                        ))
                    }
                    Some(p) => {
                        if latest.is_none_or(|q| p.date > q.date) {
                            latest = Some(p);
                        }
                    }
                }
            }
        }
        if let Some(p) = latest {
            if p.date >= g.planned {
                return Err(ScheduleError::layout(
                    GROUTING_CSV,
                    g.line,
                    3,
                    format!(
                        "{what}: block {} lift {} is poured {} ({POURS_CSV}:{})",
                        p.block, p.lift, p.date, p.line
                    ),
                ));
            }
        }
    }
    if let Some(meters) = &s.joint_meters {
        for m in meters {
            check_joint_zone(JOINT_METERS_CSV, m.line, layout, &joints, m.joint, m.zone)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_text() {
        assert_eq!(ranges(&[1, 2, 3, 5, 7, 8]), "1-3, 5, 7-8");
        assert_eq!(ranges(&[]), "");
        assert_eq!(ranges(&[4]), "4");
    }
}
