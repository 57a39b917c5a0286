//! From a URDF tree to the serial chain the model runs: the path from the root to the tool link,
//! every other branch held rigid and lumped into the link it hangs from, and clear errors for
//! files that are not URDF (xacro, SDF, MJCF).

use std::collections::HashMap;

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3, Unit, Vector3};

use super::model::{collisions, inertial, joint_info, lump, pose, Body, Inertial, JointKind, LinkInfo};
use super::{Robot, RobotError};

/// Refuses text that is not a URDF before the XML parser gives a confusing message: xacro macros
/// (which must be expanded first), SDF and MuJoCo files, and XML without a `<robot>` root.
pub(super) fn check_format(text: &str, file: &str) -> Result<(), RobotError> {
    let not_urdf = |what: &str, hint: &str| RobotError::NotUrdf {
        file: file.to_owned(),
        what: what.to_owned(),
        hint: hint.to_owned(),
    };
    // An expanded file may still declare the xacro namespace on `<robot>` (most vendors'
    // distributed URDFs do): only xacro elements or expressions that remain make it a macro file.
    if text.contains("<xacro:") || text.contains("${") || text.contains("$(arg ") || text.contains("$(find ") {
        return Err(not_urdf(
            "a xacro file (macros and `${...}` expressions)",
            &format!("expand it to plain URDF first: `xacro {file} > robot.urdf` (ROS 2: `ros2 run xacro xacro {file} -o robot.urdf`), then load robot.urdf"),
        ));
    }
    match root_element(text) {
        Some("robot") => Ok(()),
        Some("sdf") => Err(not_urdf(
            "an SDF file",
            "skillc reads URDF; use the URDF from the vendor's description package, or convert the model to URDF",
        )),
        Some("mujoco") => Err(not_urdf(
            "a MuJoCo MJCF file",
            "skillc reads URDF; use the URDF the MJCF was made from, or the vendor's URDF",
        )),
        Some(other) => Err(not_urdf(
            &format!("XML whose root element is `<{other}>`"),
            "a URDF's root element is `<robot name=\"...\">`",
        )),
        None => Err(not_urdf(
            "empty or not XML",
            "a URDF is an XML file whose root element is `<robot name=\"...\">`",
        )),
    }
}

/// The name of the first element of an XML text, after the declaration, comments and DOCTYPE.
fn root_element(text: &str) -> Option<&str> {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(after) = rest.strip_prefix("<?") {
            rest = &after[after.find("?>")? + 2..];
        } else if let Some(after) = rest.strip_prefix("<!--") {
            rest = &after[after.find("-->")? + 3..];
        } else if let Some(after) = rest.strip_prefix("<!") {
            rest = &after[after.find('>')? + 1..];
        } else if let Some(after) = rest.strip_prefix('<') {
            let end = after
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .unwrap_or(after.len());
            let name = &after[..end];
            // A namespace prefix (`<urdf:robot>`) names the same element.
            return Some(name.rsplit(':').next().unwrap_or(name)).filter(|n| !n.is_empty());
        } else {
            return None;
        }
    }
}

/// The URDF's links and joints as a tree: each link's parent joint and child joints.
struct Tree<'u> {
    urdf: &'u urdf_rs::Robot,
    link_idx: HashMap<&'u str, usize>,
    parent_joint: Vec<Option<usize>>,
    child_joints: Vec<Vec<usize>>,
    root: usize,
}

impl<'u> Tree<'u> {
    fn new(urdf: &'u urdf_rs::Robot) -> Result<Self, RobotError> {
        let link_idx: HashMap<&str, usize> = urdf
            .links
            .iter()
            .enumerate()
            .map(|(idx, link)| (link.name.as_str(), idx))
            .collect();
        let mut parent_joint: Vec<Option<usize>> = vec![None; urdf.links.len()];
        let mut child_joints: Vec<Vec<usize>> = vec![Vec::new(); urdf.links.len()];
        for (joint_idx, joint) in urdf.joints.iter().enumerate() {
            let find = |name: &str| {
                link_idx.get(name).copied().ok_or_else(|| RobotError::JointLinkMissing {
                    joint: joint.name.clone(),
                    link: name.to_owned(),
                })
            };
            let parent = find(&joint.parent.link)?;
            let child = find(&joint.child.link)?;
            if parent_joint[child].replace(joint_idx).is_some() {
                return Err(RobotError::SeveralParents {
                    link: joint.child.link.clone(),
                });
            }
            child_joints[parent].push(joint_idx);
        }
        let roots: Vec<usize> = (0..urdf.links.len())
            .filter(|idx| parent_joint[*idx].is_none())
            .collect();
        if roots.len() != 1 {
            return Err(RobotError::Roots {
                count: roots.len(),
                roots: roots
                    .iter()
                    .map(|idx| urdf.links[*idx].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let tree = Tree {
            urdf,
            link_idx,
            parent_joint,
            child_joints,
            root: roots[0],
        };
        // Every link has at most one parent and exactly one has none; a link that cannot reach
        // the root sits on a cycle.
        for link in 0..urdf.links.len() {
            tree.path_to(link)?;
        }
        Ok(tree)
    }

    fn child_of(&self, joint: usize) -> usize {
        self.link_idx[self.urdf.joints[joint].child.link.as_str()]
    }

    fn parent_of(&self, joint: usize) -> usize {
        self.link_idx[self.urdf.joints[joint].parent.link.as_str()]
    }

    /// The joints from the root to `link`, in order.
    fn path_to(&self, link: usize) -> Result<Vec<usize>, RobotError> {
        let mut joints = Vec::new();
        let mut at = link;
        while let Some(joint) = self.parent_joint[at] {
            joints.push(joint);
            if joints.len() > self.urdf.joints.len() {
                return Err(RobotError::SeveralParents {
                    link: self.urdf.links[link].name.clone(),
                });
            }
            at = self.parent_of(joint);
        }
        joints.reverse();
        Ok(joints)
    }

    fn movable_on(&self, path: &[usize]) -> usize {
        path.iter()
            .filter(|joint| self.urdf.joints[**joint].joint_type != urdf_rs::JointType::Fixed)
            .count()
    }

    /// The tool link: the one named, or the end of the longest movable chain when it is unique.
    fn tool(&self, tool_link: Option<&str>) -> Result<usize, RobotError> {
        if let Some(name) = tool_link {
            return self.link_idx.get(name).copied().ok_or_else(|| RobotError::UnknownLink {
                name: name.to_owned(),
                robot: self.urdf.name.clone(),
                known: self
                    .urdf
                    .links
                    .iter()
                    .map(|link| link.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let leaves: Vec<usize> = (0..self.urdf.links.len())
            .filter(|link| self.child_joints[*link].is_empty())
            .collect();
        let mut best: Vec<(usize, usize)> = Vec::new();
        for leaf in leaves {
            let movable = self.movable_on(&self.path_to(leaf)?);
            match best.first() {
                Some((_, most)) if movable < *most => {}
                Some((_, most)) if movable == *most => best.push((leaf, movable)),
                _ => best = vec![(leaf, movable)],
            }
        }
        match best.as_slice() {
            [(leaf, _)] => Ok(*leaf),
            several => Err(RobotError::AmbiguousTool {
                robot: self.urdf.name.clone(),
                ends: several
                    .iter()
                    .map(|(leaf, _)| format!("`{}`", self.urdf.links[*leaf].name))
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }
}

/// The pose a held (off-chain) joint adds at `value` (rad or m).
fn held_motion(kind: JointKind, axis: &Vector3<f64>, value: f64) -> IsometryMatrix3<f64> {
    match kind {
        JointKind::Revolute => IsometryMatrix3::from_parts(
            Translation3::identity(),
            Rotation3::from_axis_angle(&Unit::new_normalize(*axis), value),
        ),
        JointKind::Prismatic => IsometryMatrix3::from_parts(Translation3::from(axis * value), Rotation3::identity()),
    }
}

/// The value a joint off the chain is held at: 0 where its limits allow, else the limit nearest 0.
fn held_value(joint: &urdf_rs::Joint) -> f64 {
    match joint.joint_type {
        urdf_rs::JointType::Continuous => 0.0,
        _ if joint.limit.lower <= joint.limit.upper => 0f64.clamp(joint.limit.lower, joint.limit.upper),
        _ => 0.0,
    }
}

/// Refuses a number in an attribute that parses to infinity without being the word `inf`
/// (`effort="1e309"`): the XML reader would turn it into infinity and switch a limit off
/// silently. Linear in the text.
pub(super) fn check_numbers(text: &str, file: &str) -> Result<(), RobotError> {
    let bytes = text.as_bytes();
    let mut element_start = None;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            // A comment's quotes are prose (`don't`): skip it whole.
            b'<' if bytes[i..].starts_with(b"<!--") => {
                let Some(len) = text[i..].find("-->") else {
                    return Ok(());
                };
                i += len + 3;
                continue;
            }
            b'<' => element_start = Some(i + 1),
            b'>' => element_start = None,
            quote @ (b'"' | b'\'') if element_start.is_some() => {
                let Some(len) = bytes[i + 1..].iter().position(|b| *b == quote) else {
                    return Ok(()); // unterminated: the XML parser says so
                };
                let value = &text[i + 1..i + 1 + len];
                for token in value.split_ascii_whitespace() {
                    let word = token.trim_start_matches(['+', '-']).to_ascii_lowercase();
                    let overflows =
                        token.parse::<f64>().is_ok_and(f64::is_infinite) && word != "inf" && word != "infinity";
                    if overflows {
                        let line = 1 + bytes[..i].iter().filter(|b| **b == b'\n').count();
                        let before = &text[element_start.unwrap_or(i)..i];
                        let element = before
                            .split(|c: char| c.is_whitespace() || c == '/')
                            .next()
                            .unwrap_or("");
                        let attribute = before
                            .trim_end()
                            .trim_end_matches('=')
                            .trim_end()
                            .rsplit(|c: char| c.is_whitespace())
                            .next()
                            .unwrap_or("");
                        return Err(RobotError::Overflow {
                            file: file.to_owned(),
                            line,
                            element: element.to_owned(),
                            attribute: attribute.to_owned(),
                            text: token.to_owned(),
                        });
                    }
                }
                i += len + 2;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

/// A link's mass properties, with the leniency a link fixed to the base earns: its mass and
/// inertia never enter the dynamics, so inconsistent values there are a note, not an error.
fn link_inertial(link: &urdf_rs::Link, on_base: bool, notes: &mut Vec<String>) -> Result<Inertial, RobotError> {
    match inertial(link) {
        Ok((inertial, _)) => {
            let massless_tensor = inertial.mass == 0.0 && inertial.inertia.iter().any(|v| *v != 0.0);
            if !on_base && massless_tensor {
                notes.push(format!(
                    "link `{}` has zero mass but an inertia tensor: its inertia is lumped as given into the body it is fixed to",
                    link.name
                ));
            }
            if on_base && massless_tensor {
                notes.push(format!(
                    "link `{}` is fixed to the base, so its inertial values are ignored (zero mass with an inertia tensor)",
                    link.name
                ));
                return Ok(Inertial {
                    mass: 0.0,
                    com: Vector3::zeros(),
                    inertia: Matrix3::zeros(),
                });
            }
            if on_base && inertial.mass > 0.0 {
                notes.push(format!(
                    "link `{}` is fixed to the base: its mass ({} kg) and inertia do not enter the dynamics",
                    link.name, inertial.mass
                ));
            }
            Ok(inertial)
        }
        Err(
            err @ (RobotError::ZeroMass { .. } | RobotError::InertiaNotSpd { .. } | RobotError::NegativeMass { .. }),
        ) if on_base => {
            notes.push(format!(
                "link `{}` is fixed to the base, so its inertial values are ignored ({err})",
                link.name
            ));
            Ok(Inertial {
                mass: 0.0,
                com: Vector3::zeros(),
                inertia: Matrix3::zeros(),
            })
        }
        Err(err) => Err(err),
    }
}

/// Builds the model of the chain from the root to the tool link.
pub(super) fn build(urdf: &urdf_rs::Robot, tool_link: Option<&str>) -> Result<Robot, RobotError> {
    let tree = Tree::new(urdf)?;
    let tool = tree.tool(tool_link)?;
    let path = tree.path_to(tool)?;
    let mut notes = Vec::new();

    let mut joints = Vec::new();
    let mut links: Vec<LinkInfo> = Vec::new();
    let mut bodies: Vec<Body> = Vec::new();
    // Chain links in order: the root, then the child of each joint on the path.
    let mut chain = vec![(tree.root, None)];
    chain.extend(path.iter().map(|joint| (tree.child_of(*joint), Some(*joint))));
    // The current link frame in the current body's frame (or the base frame before the first joint).
    let mut link_in_body = IsometryMatrix3::identity();
    for (urdf_link_idx, via) in &chain {
        let urdf_link = &urdf.links[*urdf_link_idx];
        if let Some(joint_idx) = via {
            let urdf_joint = &urdf.joints[*joint_idx];
            let origin = pose(&urdf_joint.origin, || format!("joint {} origin", urdf_joint.name))?;
            match joint_info(urdf_joint, &mut notes)? {
                None => link_in_body *= origin,
                Some(info) => {
                    let joint_frame = link_in_body * origin;
                    bodies.push(Body {
                        rot0: *joint_frame.rotation.matrix(),
                        pos0: joint_frame.translation.vector,
                        axis: info.axis,
                        kind: info.kind,
                        mass: 0.0,
                        com: Vector3::zeros(),
                        inertia: Matrix3::zeros(),
                    });
                    joints.push(info);
                    link_in_body = IsometryMatrix3::identity();
                }
            }
        }
        let body = joints.len().checked_sub(1);
        let link_inertial = link_inertial(urdf_link, body.is_none(), &mut notes)?;
        if let Some(body_idx) = body {
            lump(&mut bodies[body_idx], &link_inertial, &link_in_body);
        }
        links.push(LinkInfo {
            name: urdf_link.name.clone(),
            body,
            link_in_body,
            inertial: link_inertial,
            collisions: collisions(urdf_link)?,
        });
    }
    attach_branches(&tree, &chain, &mut links, &mut bodies, &mut notes)?;

    for (body, joint) in bodies.iter().zip(&joints) {
        if body.mass <= 0.0 {
            return Err(RobotError::MissingInertial {
                joint: joint.name.clone(),
                link: joint.child_link.clone(),
            });
        }
    }
    let tool_link = chain.len() - 1;
    if joints.is_empty() || links[tool_link].body.is_none() {
        return Err(RobotError::NoMovingJoint {
            robot: urdf.name.clone(),
            tool: links[tool_link].name.clone(),
        });
    }
    Ok(Robot {
        name: urdf.name.clone(),
        joints,
        links,
        bodies,
        tool_link,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        notes,
    })
}

/// Appends every link off the chain, held rigid on the chain link it hangs from: joints at their
/// held value, mass and inertia lumped into that link's body (ignored on the base).
fn attach_branches(
    tree: &Tree<'_>,
    chain: &[(usize, Option<usize>)],
    links: &mut Vec<LinkInfo>,
    bodies: &mut [Body],
    notes: &mut Vec<String>,
) -> Result<(), RobotError> {
    let urdf = tree.urdf;
    let on_chain: Vec<usize> = chain.iter().map(|(link, _)| *link).collect();
    for (chain_pos, (link, _)) in chain.iter().enumerate() {
        let anchor = &links[chain_pos];
        let (body, anchor_in_body) = (anchor.body, anchor.link_in_body);
        let mut held = Vec::new();
        let mut mass = 0.0;
        let attached_before = links.len();
        // Depth-first over the subtrees that leave the chain at this link.
        let mut stack: Vec<(usize, IsometryMatrix3<f64>)> = tree.child_joints[*link]
            .iter()
            .filter(|joint| !on_chain.contains(&tree.child_of(**joint)))
            .map(|joint| (*joint, anchor_in_body))
            .collect();
        while let Some((joint_idx, parent_in_body)) = stack.pop() {
            let joint = &urdf.joints[joint_idx];
            let origin = pose(&joint.origin, || format!("joint {} origin", joint.name))?;
            let mut in_body = parent_in_body * origin;
            if joint.joint_type != urdf_rs::JointType::Fixed {
                let mut ignored = Vec::new();
                let info = joint_info(joint, &mut ignored)?.expect("a movable joint");
                let value = held_value(joint);
                in_body *= held_motion(info.kind, &info.axis, value);
                let unit = if info.kind == JointKind::Revolute { "rad" } else { "m" };
                held.push(format!("`{}` at {value} {unit}", joint.name));
            }
            let child = tree.child_of(joint_idx);
            let urdf_link = &urdf.links[child];
            let link_inertial = link_inertial(urdf_link, body.is_none(), notes)?;
            if let Some(body_idx) = body {
                lump(&mut bodies[body_idx], &link_inertial, &in_body);
                mass += link_inertial.mass;
            }
            links.push(LinkInfo {
                name: urdf_link.name.clone(),
                body,
                link_in_body: in_body,
                inertial: link_inertial,
                collisions: collisions(urdf_link)?,
            });
            stack.extend(tree.child_joints[child].iter().map(|joint| (*joint, in_body)));
        }
        if links.len() > attached_before {
            let name = &urdf.links[*link].name;
            let held_text = if held.is_empty() {
                String::new()
            } else {
                format!("; joints held: {}", held.join(", "))
            };
            if body.is_some() {
                notes.push(format!(
                    "the branch at link `{name}` is not on the chain to the tool: held rigid, {mass} kg lumped into `{name}`{held_text}"
                ));
            } else {
                notes.push(format!(
                    "the branch at link `{name}` is fixed to the base: held rigid{held_text}"
                ));
            }
        }
    }
    Ok(())
}
