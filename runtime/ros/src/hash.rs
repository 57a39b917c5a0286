//! ROS 2 type hashes (REP 2011, `RIHS01_…`): the SHA-256 of a type's description, computed from
//! the same field lists [`MsgType::definition`] writes as MCAP schemas, so one table says what a
//! message holds.
//!
//! The description is what `rosidl` hashes: a JSON object with the type's own description and
//! those of every type it refers to (directly or not, sorted by name), each a `type_name` and its
//! `fields`; a field is its `name` and its `type` (`type_id`, `capacity`, `string_capacity`,
//! `nested_type_name`); default values and comments take no part. The JSON is written with
//! `", "` and `": "` as separators, keys in that order. `type_id`s are those of
//! `type_description_interfaces/msg/FieldType`: a nested type is 1, `int32` 6, `uint32` 7,
//! `float64` 11, `string` 17; an unbounded sequence (`T[]`) adds 144.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use sha2::{Digest, Sha256};

use crate::msgs::{fields_of, MsgType};

/// `type_id` of a nested message type.
const NESTED: u32 = 1;
/// What an unbounded sequence (`T[]`) adds to its element's `type_id`.
const UNBOUNDED_SEQUENCE: u32 = 144;

/// The `type_id` of a primitive field type, `None` for a message type.
fn primitive_id(name: &str) -> Option<u32> {
    Some(match name {
        "bool" => 15,
        "byte" => 16,
        "char" => 13,
        "float32" => 10,
        "float64" => 11,
        "int8" => 2,
        "uint8" => 3,
        "int16" => 4,
        "uint16" => 5,
        "int32" => 6,
        "uint32" => 7,
        "int64" => 8,
        "uint64" => 9,
        "string" => 17,
        "wstring" => 18,
        _ => return None,
    })
}

/// `pkg/Type` (as definitions write it) → `pkg/msg/Type` (as type descriptions name it).
fn full_name(short: &str) -> String {
    match short.split_once('/') {
        Some((pkg, ty)) if !ty.starts_with("msg/") => format!("{pkg}/msg/{ty}"),
        _ => short.to_owned(),
    }
}

/// One field of a definition: its name, its `type_id` and the message type it nests (`pkg/Type`).
fn parse_fields(text: &str) -> Vec<(&str, u32, Option<&str>)> {
    text.lines()
        .filter_map(|line| {
            let mut words = line.split_whitespace();
            let ty = words.next()?;
            let name = words.next()?;
            let (element, sequence) = match ty.strip_suffix("[]") {
                Some(element) => (element, UNBOUNDED_SEQUENCE),
                None => (ty, 0),
            };
            Some(match primitive_id(element) {
                Some(id) => (name, id + sequence, None),
                None => (name, NESTED + sequence, Some(element)),
            })
        })
        .collect()
}

/// Appends one type's `{"type_name": ..., "fields": [...]}`.
fn describe(out: &mut String, type_name: &str, fields: &str) {
    let _ = write!(out, "{{\"type_name\": \"{}\", \"fields\": [", full_name(type_name));
    for (index, (name, id, nested)) in parse_fields(fields).into_iter().enumerate() {
        if index > 0 {
            out.push_str(", ");
        }
        let _ = write!(
            out,
            "{{\"name\": \"{name}\", \"type\": {{\"type_id\": {id}, \"capacity\": 0, \"string_capacity\": 0, \
             \"nested_type_name\": \"{}\"}}}}",
            nested.map(full_name).unwrap_or_default()
        );
    }
    out.push_str("]}");
}

/// Every message type `fields` refers to, directly or through another, as `pkg/Type`.
fn referenced(fields: &str, into: &mut BTreeSet<String>) {
    for (_, _, nested) in parse_fields(fields) {
        if let Some(nested) = nested {
            if into.insert(nested.to_owned()) {
                referenced(fields_of(nested), into);
            }
        }
    }
}

/// The JSON text REP 2011 hashes for `ty`.
pub fn type_description_json(ty: MsgType) -> String {
    description_json(ty.schema_name(), ty.own_fields())
}

/// The JSON text REP 2011 hashes for the type `type_name` with fields `own`.
fn description_json(type_name: &str, own: &str) -> String {
    let mut refs = BTreeSet::new();
    referenced(own, &mut refs);
    // Sorted by their full names, as rosidl sorts them (`pkg/msg/Type`; the same order as the
    // short names' unless a package name is a prefix of another's).
    let mut refs: Vec<String> = refs.into_iter().collect();
    refs.sort_by_key(|name| full_name(name));
    let mut out = String::with_capacity(2048);
    out.push_str("{\"type_description\": ");
    describe(&mut out, type_name, own);
    out.push_str(", \"referenced_type_descriptions\": [");
    for (index, name) in refs.iter().enumerate() {
        if index > 0 {
            out.push_str(", ");
        }
        describe(&mut out, name, fields_of(name));
    }
    out.push_str("]}");
    out
}

/// The type hash as ROS 2 writes it: `RIHS01_` and the SHA-256 of the description in hex.
pub fn type_hash(ty: MsgType) -> String {
    hash_of(&type_description_json(ty))
}

fn hash_of(description: &str) -> String {
    let digest = Sha256::digest(description.as_bytes());
    let mut out = String::from("RIHS01_");
    for byte in digest {
        let _ = write!(out, "{byte:02x}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hashes ROS 2 Jazzy's interface packages carry (their `.json` type descriptions).
    #[test]
    fn hashes_match_the_ones_jazzy_ships() {
        for (ty, hash) in [
            (
                MsgType::JointState,
                "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
            ),
            (
                MsgType::WrenchStamped,
                "RIHS01_8dc3deaf06b2ab281f9f9a742a8961c328ca7cec16e3fd6586d3a5c83fa78f77",
            ),
            (
                MsgType::Float64MultiArray,
                "RIHS01_1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f",
            ),
        ] {
            assert_eq!(
                type_hash(ty),
                hash,
                "{}: {}",
                ty.schema_name(),
                type_description_json(ty)
            );
        }
    }

    /// `visualization_msgs/Marker`'s hash as the generated `rosidl` code of a release with the
    /// texture and mesh-file fields carries it: the marker's field list (order, types, nested
    /// types) is the one ROS 2 builds, or a viewer would misread every field after a mistake.
    #[test]
    fn the_marker_hashes_as_ros_2_builds_it() {
        let marker = "visualization_msgs/Marker";
        assert_eq!(
            hash_of(&description_json(marker, fields_of(marker))),
            "RIHS01_45b13ccf791f225962bf74e746f9644518855d783a6f42ba0cc14fde2b4f3ce0"
        );
    }

    #[test]
    fn a_description_names_each_referenced_type_once_in_order() {
        let json = type_description_json(MsgType::WrenchStamped);
        let names: Vec<&str> = json
            .match_indices("\"type_name\": \"")
            .map(|(at, key)| {
                let rest = &json[at + key.len()..];
                &rest[..rest.find('"').unwrap_or(rest.len())]
            })
            .collect();
        assert_eq!(
            names,
            [
                "geometry_msgs/msg/WrenchStamped",
                "builtin_interfaces/msg/Time",
                "geometry_msgs/msg/Vector3",
                "geometry_msgs/msg/Wrench",
                "std_msgs/msg/Header",
            ]
        );
    }
}
