//! The Foxglove layout shipped in `docs/foxglove/`: every panel it places is configured and titled, and
//! every topic and message path it shows is one `skillc run -o log.mcap` writes, down to a field
//! of the message's definition as the bag's schema carries it.
#![cfg(feature = "mcap")]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde_json::Value;
use skill_ros::bag::RunLogTopics;
use skill_ros::msgs::MsgType;

fn layout() -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/foxglove/skillc-run.json");
    let text = std::fs::read_to_string(&path).expect("the layout ships");
    serde_json::from_str(&text).expect("the layout is JSON")
}

/// The panel ids at the leaves of the layout's split tree.
fn placed(node: &Value, into: &mut BTreeSet<String>) {
    match node {
        Value::String(id) => {
            into.insert(id.clone());
        }
        Value::Object(split) => {
            for side in ["first", "second"] {
                placed(split.get(side).expect("a split has two sides"), into);
            }
        }
        other => panic!("a layout node is a panel id or a split, not {other}"),
    }
}

/// A `ros2msg` definition as its types' fields: the top type under `""`, each `MSG: pkg/Type`
/// under its name; a field is `(type, name)`.
fn definition_types(text: &str) -> BTreeMap<String, Vec<(String, String)>> {
    let mut types = BTreeMap::new();
    let mut current = String::new();
    for line in text.lines() {
        if line.starts_with("===") {
            continue;
        }
        if let Some(name) = line.strip_prefix("MSG: ") {
            current = name.trim().to_owned();
            continue;
        }
        let mut words = line.split_whitespace();
        if let (Some(ty), Some(name)) = (words.next(), words.next()) {
            if !name.contains('=') {
                types
                    .entry(current.clone())
                    .or_insert_with(Vec::new)
                    .push((ty.to_owned(), name.to_owned()));
            }
        }
    }
    types
}

/// Checks that `path` (`/topic.field.field`) ends on a plain field of a topic the run log writes.
fn check_path(path: &str) {
    let (topic, fields) = path.split_at(path.find('.').unwrap_or(path.len()));
    let (_, ty) = RunLogTopics::ALL
        .iter()
        .find(|(name, _)| *name == topic)
        .unwrap_or_else(|| panic!("`{path}`: the run log has no topic `{topic}`"));
    let types = definition_types(&ty.definition());
    let mut fields_here = &types[""];
    let mut last_type = String::new();
    for field in fields.trim_start_matches('.').split('.') {
        let (field_type, _) = fields_here
            .iter()
            .find(|(_, name)| name == field)
            .unwrap_or_else(|| panic!("`{path}`: {} has no field `{field}`", ty.schema_name()));
        last_type = field_type.clone();
        if let Some(nested) = types.get(field_type.as_str()) {
            fields_here = nested;
        }
    }
    assert!(
        ["float64", "float32", "string", "int32", "uint32"].contains(&last_type.as_str()),
        "`{path}` ends on a {last_type}, not on a value a plot or a state panel shows"
    );
}

#[test]
fn every_panel_placed_is_configured_and_every_configured_panel_placed() {
    let layout = layout();
    let mut ids = BTreeSet::new();
    placed(&layout["layout"], &mut ids);
    let configured: BTreeSet<String> = layout["configById"]
        .as_object()
        .expect("configById")
        .keys()
        .cloned()
        .collect();
    assert_eq!(ids, configured);
    assert!(ids.iter().any(|id| id.starts_with("3D!")), "a 3-D panel");
    // Foxglove and Lichtblick title a panel by `foxglovePanelTitle`; a `title` key is ignored
    // (Lichtblick 1.10 showed every plot as "Plot" while the layout said `title`).
    for (id, config) in layout["configById"].as_object().expect("configById") {
        let title = config["foxglovePanelTitle"].as_str().unwrap_or_default();
        assert!(!title.is_empty(), "panel {id} has no foxglovePanelTitle");
        assert!(
            config.get("title").is_none(),
            "panel {id} has a `title`, which viewers ignore"
        );
    }
}

#[test]
fn every_topic_and_path_the_layout_shows_is_written_by_a_run() {
    let layout = layout();
    let mut paths = 0;
    for (id, config) in layout["configById"].as_object().expect("configById") {
        if id.starts_with("3D!") {
            assert_eq!(config["followTf"], "base", "the run log's frames hang from `base`");
            let topics = config["topics"].as_object().expect("3D topics");
            for topic in topics.keys() {
                assert!(
                    RunLogTopics::ALL.iter().any(|(name, _)| name == topic),
                    "the 3-D panel shows `{topic}`, which no run log has"
                );
            }
            for needed in [
                RunLogTopics::ROBOT_DESCRIPTION,
                RunLogTopics::SCENE,
                RunLogTopics::CONTACT_FORCE,
            ] {
                assert_eq!(topics[needed]["visible"], true, "{needed} is shown");
            }
        }
        for path in config["paths"].as_array().into_iter().flatten() {
            check_path(path["value"].as_str().expect("a path's value"));
            paths += 1;
        }
    }
    assert!(paths >= 6, "{paths} paths");
    // The checker itself refuses what is not there.
    for bad in ["/wrench.wrench.force.w", "/nosuch.data", "/wrench.wrench.force"] {
        assert!(std::panic::catch_unwind(|| check_path(bad)).is_err(), "{bad}");
    }
    assert!(MsgType::WrenchStamped
        .definition()
        .contains("MSG: geometry_msgs/Vector3"));
}
