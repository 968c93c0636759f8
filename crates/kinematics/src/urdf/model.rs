//! A URDF's links and joints as the file gives them (lengths in mm), each
//! with its line, read with roxmltree.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Isometry3, Vector3};
use roxmltree::{Document, Node};

use super::error::{UrdfError, UrdfPlace};
use crate::geometry::origin;

/// The joint types of URDF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
}

impl Kind {
    fn parse(word: &str) -> Option<Kind> {
        Some(match word {
            "revolute" => Kind::Revolute,
            "continuous" => Kind::Continuous,
            "prismatic" => Kind::Prismatic,
            "fixed" => Kind::Fixed,
            "floating" => Kind::Floating,
            "planar" => Kind::Planar,
            _ => return None,
        })
    }

    /// The type as a URDF writes it.
    pub(crate) fn word(self) -> &'static str {
        match self {
            Kind::Revolute => "revolute",
            Kind::Continuous => "continuous",
            Kind::Prismatic => "prismatic",
            Kind::Fixed => "fixed",
            Kind::Floating => "floating",
            Kind::Planar => "planar",
        }
    }
}

/// What a `<visual>` draws, lengths in mm; a mesh's file name as written.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Shape {
    Mesh { filename: String, scale: [f64; 3] },
    Box([f64; 3]),
    Cylinder { radius: f64, length: f64 },
    Sphere(f64),
}

/// One `<visual>` of a link.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RawVisual {
    pub(crate) line: u32,
    pub(crate) origin: Isometry3<f64>,
    pub(crate) shape: Shape,
    pub(crate) color: Option<[f64; 4]>,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Link {
    pub(crate) name: String,
    pub(crate) line: u32,
    pub(crate) visuals: Vec<RawVisual>,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Joint {
    pub(crate) name: String,
    pub(crate) line: u32,
    pub(crate) kind: Kind,
    /// Link indices.
    pub(crate) parent: usize,
    pub(crate) child: usize,
    /// The child link's frame in the parent's at angle 0, mm.
    pub(crate) origin: Isometry3<f64>,
    /// As written (not normalised).
    pub(crate) axis: Vector3<f64>,
    /// `lower`, `upper` (rad) and `velocity` (rad/s) of `<limit>`.
    pub(crate) lower: Option<f64>,
    pub(crate) upper: Option<f64>,
    pub(crate) velocity: Option<f64>,
}

/// A URDF's links and joints.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Model {
    pub(crate) links: Vec<Link>,
    pub(crate) joints: Vec<Joint>,
}

/// Reads one element's attributes, errors placed at its line.
struct Reader<'f, 'a, 'i> {
    file: &'f Path,
    node: Node<'a, 'i>,
    line: u32,
}

impl<'f, 'a, 'i> Reader<'f, 'a, 'i> {
    fn new(file: &'f Path, node: Node<'a, 'i>) -> Self {
        let line = node.document().text_pos_at(node.range().start).row;
        Reader { file, node, line }
    }

    fn error(&self, reason: String) -> UrdfError {
        UrdfError::Malformed {
            place: UrdfPlace::at(self.file, self.line),
            reason,
        }
    }

    fn text(&self, name: &str) -> Result<&'a str, UrdfError> {
        self.node.attribute(name).ok_or_else(|| {
            let tag = self.node.tag_name().name();
            self.error(format!("<{tag}> has no `{name}` attribute"))
        })
    }

    fn numbers<const N: usize>(&self, name: &str) -> Result<Option<[f64; N]>, UrdfError> {
        let Some(text) = self.node.attribute(name) else {
            return Ok(None);
        };
        let values: Vec<f64> = text
            .split_whitespace()
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .unwrap_or_default();
        let tag = self.node.tag_name().name();
        <[f64; N]>::try_from(values).map(Some).map_err(|_| {
            self.error(format!(
                "<{tag} {name}=\"{text}\">: expected {N} finite number{}",
                if N == 1 { "" } else { "s" }
            ))
        })
    }

    fn number(&self, name: &str) -> Result<Option<f64>, UrdfError> {
        Ok(self.numbers::<1>(name)?.map(|[v]| v))
    }
}

/// The element children of `node` called `tag`.
fn children<'a, 'i>(node: Node<'a, 'i>, tag: &'a str) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &'a str) -> Option<Node<'a, 'i>> {
    children(node, tag).next()
}

/// An `<origin>` child of `node` in mm (identity when absent).
fn origin_of(file: &Path, node: Node<'_, '_>) -> Result<Isometry3<f64>, UrdfError> {
    let Some(o) = child(node, "origin") else {
        return Ok(Isometry3::identity());
    };
    let r = Reader::new(file, o);
    let xyz = r.numbers::<3>("xyz")?.unwrap_or_default();
    let rpy = r.numbers::<3>("rpy")?.unwrap_or_default();
    Ok(origin(xyz.map(|m| m * 1000.0), rpy))
}

/// Parses the text of URDF `file`.
pub(crate) fn parse(text: &str, file: &Path) -> Result<Model, UrdfError> {
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        let reason = e.to_string();
        let reason = match reason.rfind(" at ") {
            Some(i) => reason[..i].to_owned(),
            None => reason,
        };
        UrdfError::Xml {
            place: UrdfPlace::at(file, pos.row),
            column: pos.col,
            reason,
        }
    })?;
    let robot = doc.root_element();
    if robot.tag_name().name() != "robot" {
        return Err(Reader::new(file, robot).error(format!(
            "the root element is <{}>; a URDF's is <robot>",
            robot.tag_name().name()
        )));
    }
    let colors = materials(file, robot)?;
    let mut links = Vec::new();
    let mut index: HashMap<&str, usize> = HashMap::new();
    for node in children(robot, "link") {
        let r = Reader::new(file, node);
        let name = r.text("name")?;
        if let Some(&first) = index.get(name) {
            let first: &Link = &links[first];
            return Err(r.error(format!(
                "link `{name}` is defined twice (first at line {})",
                first.line
            )));
        }
        index.insert(name, links.len());
        links.push(link(file, node, name, &colors)?);
    }
    let mut joints: Vec<Joint> = Vec::new();
    for node in children(robot, "joint") {
        let j = joint(file, node, &index)?;
        if let Some(first) = joints.iter().find(|f| f.name == j.name) {
            return Err(Reader::new(file, node).error(format!(
                "joint `{}` is defined twice (first at line {})",
                j.name, first.line
            )));
        }
        joints.push(j);
    }
    Ok(Model { links, joints })
}

/// The colours of the robot's named `<material>`s.
fn materials(file: &Path, robot: Node<'_, '_>) -> Result<HashMap<String, [f64; 4]>, UrdfError> {
    let mut out = HashMap::new();
    for m in children(robot, "material") {
        let name = Reader::new(file, m).text("name")?;
        if let Some(c) = child(m, "color") {
            if let Some(rgba) = Reader::new(file, c).numbers::<4>("rgba")? {
                out.insert(name.to_owned(), rgba);
            }
        }
    }
    Ok(out)
}

fn link(
    file: &Path,
    node: Node<'_, '_>,
    name: &str,
    colors: &HashMap<String, [f64; 4]>,
) -> Result<Link, UrdfError> {
    let mut visuals = Vec::new();
    for v in children(node, "visual") {
        let Some(geometry) = child(v, "geometry") else {
            continue;
        };
        let Some(shape) = shape(file, geometry)? else {
            continue;
        };
        // The shape's line: where a mesh's file name is.
        let shape_node = geometry.children().find(Node::is_element);
        let line = Reader::new(file, shape_node.unwrap_or(v)).line;
        let color = match child(v, "material") {
            None => None,
            Some(m) => match child(m, "color") {
                Some(c) => Reader::new(file, c).numbers::<4>("rgba")?,
                None => m.attribute("name").and_then(|n| colors.get(n).copied()),
            },
        };
        visuals.push(RawVisual {
            line,
            origin: origin_of(file, v)?,
            shape,
            color,
        });
    }
    Ok(Link {
        name: name.to_owned(),
        line: Reader::new(file, node).line,
        visuals,
    })
}

/// The shape inside a `<geometry>`, lengths in mm; `None` for a shape
/// servobus does not draw.
fn shape(file: &Path, geometry: Node<'_, '_>) -> Result<Option<Shape>, UrdfError> {
    let Some(node) = geometry.children().find(Node::is_element) else {
        return Ok(None);
    };
    let r = Reader::new(file, node);
    let need = |name: &str| -> Result<f64, UrdfError> {
        r.number(name)?
            .ok_or_else(|| r.error(format!("<{}> has no `{name}`", node.tag_name().name())))
    };
    Ok(Some(match node.tag_name().name() {
        "mesh" => Shape::Mesh {
            filename: r.text("filename")?.to_owned(),
            scale: r.numbers::<3>("scale")?.unwrap_or([1.0; 3]),
        },
        "box" => {
            let size = r.numbers::<3>("size")?;
            Shape::Box(
                size.ok_or_else(|| r.error("<box> has no `size`".into()))?
                    .map(|m| m * 1e3),
            )
        }
        "cylinder" => Shape::Cylinder {
            radius: need("radius")? * 1e3,
            length: need("length")? * 1e3,
        },
        "sphere" => Shape::Sphere(need("radius")? * 1e3),
        _ => return Ok(None),
    }))
}

fn joint(
    file: &Path,
    node: Node<'_, '_>,
    links: &HashMap<&str, usize>,
) -> Result<Joint, UrdfError> {
    let r = Reader::new(file, node);
    let name = r.text("name")?.to_owned();
    let word = r.text("type")?;
    let kind = Kind::parse(word).ok_or_else(|| {
        r.error(format!(
            "joint `{name}` has type `{word}`; URDF's are revolute, continuous, prismatic, \
             fixed, floating and planar"
        ))
    })?;
    let link_of = |tag: &str| -> Result<usize, UrdfError> {
        let Some(n) = child(node, tag) else {
            return Err(r.error(format!("joint `{name}` has no <{tag}>")));
        };
        let link = Reader::new(file, n).text("link")?;
        links.get(link).copied().ok_or_else(|| {
            r.error(format!(
                "joint `{name}`: <{tag} link=\"{link}\"> names no link of the file"
            ))
        })
    };
    let (parent, child_link) = (link_of("parent")?, link_of("child")?);
    let axis = match child(node, "axis") {
        Some(a) => Reader::new(file, a)
            .numbers::<3>("xyz")?
            .unwrap_or([1.0, 0.0, 0.0]),
        None => [1.0, 0.0, 0.0],
    };
    let (mut lower, mut upper, mut velocity) = (None, None, None);
    if let Some(l) = child(node, "limit") {
        let lr = Reader::new(file, l);
        lower = Some(lr.number("lower")?.unwrap_or(0.0));
        upper = Some(lr.number("upper")?.unwrap_or(0.0));
        velocity = lr.number("velocity")?.filter(|v| *v > 0.0);
    }
    Ok(Joint {
        name,
        line: r.line,
        kind,
        parent,
        child: child_link,
        origin: origin_of(file, node)?,
        axis: Vector3::from(axis),
        lower,
        upper,
        velocity,
    })
}
