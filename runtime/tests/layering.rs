//! The runtime's crates are layered one way (ARCHITECTURE.md): a controller process (the skill
//! engine, `skill-exec`) links neither the simulator nor the learner, and a plant process
//! (`skill-sim`) links no learner. Read from the manifests, transitively over the workspace's
//! own crates, so a dependency added in the wrong room fails here.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Every workspace crate of the runtime, and the tools on top of it, by folder.
const CRATES: [(&str, &str); 12] = [
    ("skill-robot", "runtime/robot"),
    ("skill-model", "runtime/model"),
    ("skill-learn", "runtime/learn"),
    ("skill-sim", "runtime/sim"),
    ("skill-exec", "runtime/exec"),
    ("skill-runtime", "runtime"),
    ("skill-ros", "runtime/ros"),
    ("skill-transport", "runtime/transport"),
    ("skill-compiler", "compiler"),
    ("skill-language-server", "language-server"),
    ("skill-kit", "kit"),
    ("skill-eval", "eval"),
];

/// Each crate's normal (not dev) dependencies, by name. Optional ones count only where a feature
/// of the crate's own turns them on by default; [`the_plant_link_leaves_the_bag_code_out`]
/// checks who turns on the ROS 2 crate's bag code.
fn manifests() -> BTreeMap<String, BTreeSet<String>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    CRATES
        .iter()
        .map(|(name, folder)| {
            let path = root.join(folder).join("Cargo.toml");
            let text = std::fs::read_to_string(&path).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
            let manifest: toml::Table = toml::from_str(&text).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
            let package = manifest["package"]["name"].as_str().expect("a package name");
            assert_eq!(package, *name, "{}", path.display());
            let deps = manifest
                .get("dependencies")
                .and_then(toml::Value::as_table)
                .map(|table| {
                    table
                        .iter()
                        .filter(|(_, spec)| spec.get("optional").and_then(toml::Value::as_bool) != Some(true))
                        .map(|(dep, _)| dep.clone())
                        .collect()
                })
                .unwrap_or_default();
            (name.to_string(), deps)
        })
        .collect()
}

/// Everything `name` links: its dependencies, and theirs among the workspace's crates.
fn links(manifests: &BTreeMap<String, BTreeSet<String>>, name: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![name.to_string()];
    while let Some(next) = todo.pop() {
        for dep in manifests.get(&next).into_iter().flatten() {
            if seen.insert(dep.clone()) {
                todo.push(dep.clone());
            }
        }
    }
    seen
}

#[test]
fn the_controller_links_neither_simulator_nor_learner_and_the_plant_no_learner() {
    let manifests = manifests();
    let exec = links(&manifests, "skill-exec");
    for banned in ["skill-sim", "skill-learn", "rapier3d", "csv"] {
        assert!(!exec.contains(banned), "skill-exec links {banned}: {exec:?}");
    }
    assert!(exec.contains("skill-robot") && exec.contains("skill-model"), "{exec:?}");
    let sim = links(&manifests, "skill-sim");
    for banned in ["skill-learn", "skill-exec", "skill-model"] {
        assert!(!sim.contains(banned), "skill-sim links {banned}: {sim:?}");
    }
    assert!(sim.contains("rapier3d"), "{sim:?}");
    let robot = links(&manifests, "skill-robot");
    assert!(
        robot.iter().all(|dep| !dep.starts_with("skill-")),
        "skill-robot depends on no other room: {robot:?}"
    );
    let model = links(&manifests, "skill-model");
    for banned in ["skill-robot", "skill-learn", "skill-sim", "skill-exec", "rapier3d"] {
        assert!(!model.contains(banned), "skill-model links {banned}: {model:?}");
    }
    let learn = links(&manifests, "skill-learn");
    for banned in ["skill-sim", "skill-exec", "rapier3d"] {
        assert!(!learn.contains(banned), "skill-learn links {banned}: {learn:?}");
    }
    // The transport moves a plant's states and commands: it links the robot model (the Plant
    // trait) and the wire format, neither the simulator, the learner nor the controller, so a
    // plant process and a controller process each add only it.
    let transport = links(&manifests, "skill-transport");
    for banned in ["skill-sim", "skill-learn", "skill-exec", "skill-model", "rapier3d"] {
        assert!(
            !transport.contains(banned),
            "skill-transport links {banned}: {transport:?}"
        );
    }
    assert!(
        transport.contains("zenoh") && transport.contains("skill-ros"),
        "{transport:?}"
    );
    let ros = links(&manifests, "skill-ros");
    assert!(
        ros.iter().all(|dep| !dep.starts_with("skill-") && dep != "zenoh"),
        "skill-ros is the wire format alone: {ros:?}"
    );
    // The one place two rooms meet.
    let runtime = links(&manifests, "skill-runtime");
    for needed in ["skill-sim", "skill-exec", "skill-learn"] {
        assert!(runtime.contains(needed), "{runtime:?}");
    }
}

/// Reads a manifest of the workspace by folder.
fn manifest(folder: &str) -> toml::Table {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(folder)
        .join("Cargo.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
    toml::from_str(&text).unwrap_or_else(|err| panic!("{}: {err}", path.display()))
}

#[test]
fn the_plant_link_leaves_the_bag_code_out() {
    // skill-ros's bag code (its `mcap` feature) links the learner, the controller and the
    // simulator; the plant's link must take the messages alone.
    let ros = manifest("runtime/ros");
    let bag = ros["features"]["mcap"]
        .as_array()
        .expect("skill-ros has an `mcap` feature");
    assert!(bag.iter().any(|dep| dep.as_str() == Some("dep:skill-learn")), "{bag:?}");
    assert!(
        ros["features"].get("default").is_none(),
        "skill-ros turns nothing on by default"
    );
    let transport = manifest("runtime/transport");
    let spec = &transport["dependencies"]["skill-ros"];
    assert!(
        spec.get("features").is_none(),
        "skill-transport turns on skill-ros features: {spec:?}"
    );
}

#[test]
fn the_language_server_links_the_compiler_alone() {
    let manifests = manifests();
    let server = links(&manifests, "skill-language-server");
    assert!(server.contains("skill-compiler"), "{server:?}");
    for banned in ["skill-runtime", "skill-kit", "skill-eval", "rapier3d", "skill-ros"] {
        assert!(
            !server.contains(banned),
            "skill-language-server links {banned}: {server:?}"
        );
    }
    let kit = links(&manifests, "skill-kit");
    assert!(
        !kit.contains("skill-eval"),
        "skill-kit is below the eval harness: {kit:?}"
    );
}
