//! Sweep designs: which points a sweep runs, and their ids.
//!
//! A design is written in the sweep file as one of
//!
//! ```ron
//! design: Grid([ (path: "substrate.width", values: [4.0, 6.0]), (path: ..., values: ...) ]),
//! design: Zip([ ... ]),          // axes of equal length, in lock-step
//! design: OneAtATime([ ... ]),   // the base point, then each axis varied alone
//! design: LatinHypercube(n: 20, seed: 1, axes: [ (path: ..., values: Range(start: 1.0, stop: 2.0)) ]),
//! ```
//!
//! An axis's `values` is a list of RON values (`[4.0, 6.0]`, `[On, OffAfter(9.0)]`), or
//! `Range(start: a, stop: b, n: k)` (k equally spaced values from a to b, both included)
//! or `LogRange(start: a, stop: b, n: k)` (k values equally spaced in log, a, b > 0).
//! A Latin hypercube samples each axis's `Range` / `LogRange` (without `n`: the design's
//! `n` is the number of points) by stratified random sampling with the given seed.
//!
//! An axis may instead be a list of named **variants**, each a set of overrides applied
//! together (Grid, Zip and one-at-a-time designs):
//!
//! ```ron
//! (name: "scene", variants: [
//!     (name: "flat", set: ["substrate=Flat(y_s: -2.0)", "phases.t_end=40000.0"]),
//!     (name: "push-pull", set: []),
//! ]),
//! ```
//!
//! The axis's column in `sweep.csv` is its name and a point's value there is the variant's
//! name. This is how one sweep runs several scenes of one base case, or readings of a
//! paper that change several fields at once.

use ron::value::RawValue;
use serde::{Deserialize, Serialize};

/// One axis as written in the sweep file: `(path, values)`, or `(name, variants)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    /// Dotted path into the case (as for `--set`).
    #[serde(default, deserialize_with = "super::present")]
    pub path: Option<String>,
    /// A list of RON values, or `Range(...)` / `LogRange(...)`.
    #[serde(default, deserialize_with = "super::present")]
    pub values: Option<Box<RawValue>>,
    /// Name of a variant axis (its column in `sweep.csv`).
    #[serde(default, deserialize_with = "super::present")]
    pub name: Option<String>,
    /// The variants of a variant axis.
    #[serde(default, deserialize_with = "super::present")]
    pub variants: Option<Vec<Variant>>,
}

/// One value of a variant axis: a name and the overrides it applies (`PATH=VALUE`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// The name (the axis's value in `sweep.csv`, and in a table's rows or columns).
    pub name: String,
    /// Overrides applied together, in order.
    #[serde(default)]
    pub set: Vec<String>,
}

/// The design as written in the sweep file.
#[derive(Debug, Clone, Deserialize)]
pub enum DesignSpec {
    /// Every combination of the axes' values.
    Grid(Vec<AxisSpec>),
    /// The axes' values in lock-step (equal lengths).
    Zip(Vec<AxisSpec>),
    /// The base case, then each axis's values with the other fields at the base's.
    OneAtATime(Vec<AxisSpec>),
    /// `n` points sampled over the axes' ranges, stratified in each axis.
    LatinHypercube {
        /// Number of points.
        n: usize,
        /// Seed of the random sampling (the same seed gives the same points).
        seed: u64,
        /// The axes: each a `Range` or `LogRange` without `n`.
        axes: Vec<AxisSpec>,
    },
}

/// A range of values: `Range(start, stop, n)` or `LogRange(start, stop, n)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
enum Generator {
    Range {
        start: f64,
        stop: f64,
        #[serde(default)]
        n: Option<usize>,
    },
    LogRange {
        start: f64,
        stop: f64,
        #[serde(default)]
        n: Option<usize>,
    },
}

/// The kind of design.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kind {
    /// Every combination.
    Grid,
    /// Lock-step.
    Zip,
    /// Local sensitivities around the base.
    OneAtATime,
    /// Latin hypercube sample.
    LatinHypercube,
}

/// A continuous range of an axis (Latin hypercube).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// Lower end.
    pub start: f64,
    /// Upper end.
    pub stop: f64,
    /// Sampled uniformly in log.
    pub log: bool,
}

/// An axis with its values resolved to RON text.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// Dotted path into the case; a variant axis's name.
    pub path: String,
    /// The values, as RON text (empty for a Latin hypercube's axis); a variant axis's
    /// variant names.
    pub values: Vec<String>,
    /// A variant axis's overrides, one list per value (empty for a path axis).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sets: Vec<Vec<String>>,
    /// The sampled range (Latin hypercube).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval: Option<Interval>,
}

/// A design with its axes resolved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Design {
    /// The kind.
    pub kind: Kind,
    /// The axes.
    pub axes: Vec<Axis>,
    /// Latin hypercube: number of points and seed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample: Option<(usize, u64)>,
}

/// One point of a design: its id and, per axis, the value it sets (`None`: the axis is
/// left at the base's value, as for the other axes of a one-at-a-time point).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignPoint {
    /// Stable id: also the point's directory name.
    pub id: String,
    /// Per axis, the RON text of the value set, if any.
    pub values: Vec<Option<String>>,
}

/// A number as RON text: rounded to 12 significant digits (so that `Range` steps print
/// as `0.3`, not `0.30000000000000004`), always with a decimal point or exponent.
pub fn fmt_number(v: f64) -> String {
    let rounded: f64 = format!("{v:.11e}").parse().unwrap_or(v);
    let s = format!("{rounded}");
    if s.contains(['.', 'e', 'E']) || !rounded.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

impl Generator {
    fn values(&self, axis: &str) -> Result<Vec<String>, String> {
        let (start, stop, n, log) = match *self {
            Generator::Range { start, stop, n } => (start, stop, n, false),
            Generator::LogRange { start, stop, n } => (start, stop, n, true),
        };
        let interval = self.interval(axis)?;
        let Some(n) = n else {
            return Err(format!(
                "axis `{axis}`: the range needs `n`, its number of values (n >= 1)"
            ));
        };
        if n == 0 {
            return Err(format!("axis `{axis}`: n = 0 (must satisfy n >= 1)"));
        }
        let _ = interval;
        Ok((0..n)
            .map(|k| {
                let w = if n == 1 {
                    0.0
                } else {
                    k as f64 / (n - 1) as f64
                };
                let v = if log {
                    (start.ln() + w * (stop.ln() - start.ln())).exp()
                } else {
                    start + w * (stop - start)
                };
                fmt_number(v)
            })
            .collect())
    }

    fn interval(&self, axis: &str) -> Result<Interval, String> {
        let (start, stop, log) = match *self {
            Generator::Range { start, stop, .. } => (start, stop, false),
            Generator::LogRange { start, stop, .. } => (start, stop, true),
        };
        if !(start.is_finite() && stop.is_finite()) {
            return Err(format!(
                "axis `{axis}`: start = {start}, stop = {stop} must be finite"
            ));
        }
        if log && !(start > 0.0 && stop > 0.0) {
            return Err(format!(
                "axis `{axis}`: LogRange needs start > 0 and stop > 0 (start = {start}, stop = {stop})"
            ));
        }
        Ok(Interval { start, stop, log })
    }
}

fn parse_generator(text: &str, axis: &str) -> Result<Generator, String> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<Generator>(text)
        .map_err(|e| {
            format!(
                "axis `{axis}`: values must be a list `[...]`, `Range(start: a, stop: b, n: k)` or \
                 `LogRange(start: a, stop: b, n: k)`: {} in `{text}`",
                e.code
            )
        })
}

fn list_values(text: &str, axis: &str) -> Result<Vec<String>, String> {
    let items: Vec<Box<RawValue>> = ron::Options::default()
        .from_str(text)
        .map_err(|e| format!("axis `{axis}`: values `{text}`: {}", e.code))?;
    if items.is_empty() {
        return Err(format!("axis `{axis}`: no values"));
    }
    Ok(items
        .iter()
        .map(|v| v.get_ron().trim().to_string())
        .collect())
}

/// A variant axis: names checked (not empty, one line, not repeated), overrides parsed.
fn resolve_variants(name: &str, variants: &[Variant], sampled: bool) -> Result<Axis, String> {
    let name = name.trim().to_string();
    if name.is_empty() || name.contains(['\n', '\r']) {
        return Err(format!("variant axis name {name:?}: one line, not empty"));
    }
    if sampled {
        return Err(format!(
            "axis `{name}`: a LatinHypercube samples ranges, not variants"
        ));
    }
    if variants.is_empty() {
        return Err(format!("axis `{name}`: no variants"));
    }
    let mut values: Vec<String> = Vec::new();
    for v in variants {
        let n = v.name.trim().to_string();
        if n.is_empty() || n.contains(['\n', '\r']) {
            return Err(format!(
                "axis `{name}`: variant name {:?}: one line, not empty",
                v.name
            ));
        }
        if values.contains(&n) {
            return Err(format!("axis `{name}`: variant `{n}` is given twice"));
        }
        for o in &v.set {
            crate::case::Override::parse(o)
                .map_err(|e| format!("axis `{name}`: variant `{n}`: {e}"))?;
        }
        values.push(n);
    }
    Ok(Axis {
        path: name,
        values,
        sets: variants.iter().map(|v| v.set.clone()).collect(),
        interval: None,
    })
}

fn resolve_axis(spec: &AxisSpec, sampled: bool) -> Result<Axis, String> {
    let (path, values) = match (&spec.path, &spec.values, &spec.name, &spec.variants) {
        (Some(p), Some(v), None, None) => (p, v),
        (None, None, Some(n), Some(v)) => return resolve_variants(n, v, sampled),
        _ => {
            return Err(
                "an axis is `(path: \"a.b\", values: ...)` or `(name: \"...\", variants: [(name: \"...\", set: [...]), ...])`"
                    .into(),
            );
        }
    };
    let path = path.trim().to_string();
    crate::case::Override::new(&path, "0").map_err(|e| format!("axis path `{path}`: {e}"))?;
    let text = values.get_ron().trim();
    if sampled {
        if text.starts_with('[') {
            return Err(format!(
                "axis `{path}`: a LatinHypercube samples ranges: write \
                 `values: Range(start: a, stop: b)` or `LogRange(start: a, stop: b)`"
            ));
        }
        let g = parse_generator(text, &path)?;
        if matches!(
            g,
            Generator::Range { n: Some(_), .. } | Generator::LogRange { n: Some(_), .. }
        ) {
            return Err(format!(
                "axis `{path}`: leave out `n`: the LatinHypercube's own `n` is the number of points"
            ));
        }
        let interval = g.interval(&path)?;
        return Ok(Axis {
            path,
            values: Vec::new(),
            sets: Vec::new(),
            interval: Some(interval),
        });
    }
    let values = if text.starts_with('[') {
        list_values(text, &path)?
    } else {
        parse_generator(text, &path)?.values(&path)?
    };
    Ok(Axis {
        path,
        values,
        sets: Vec::new(),
        interval: None,
    })
}

impl Axis {
    /// Whether the axis is a list of variants (named sets of overrides).
    pub fn is_variants(&self) -> bool {
        !self.sets.is_empty()
    }

    /// The overrides of the variant named `name` (a variant axis only).
    pub fn variant_set(&self, name: &str) -> Option<&[String]> {
        let k = self.values.iter().position(|v| v == name)?;
        self.sets.get(k).map(Vec::as_slice)
    }
}

/// Why a design cannot be resolved: the message names the axis and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct DesignError(pub String);

impl Design {
    /// Resolves the axes' values; the message names the axis and what is wrong.
    pub fn from_spec(spec: &DesignSpec) -> Result<Design, DesignError> {
        let (kind, axes, sample) = match spec {
            DesignSpec::Grid(a) => (Kind::Grid, a, None),
            DesignSpec::Zip(a) => (Kind::Zip, a, None),
            DesignSpec::OneAtATime(a) => (Kind::OneAtATime, a, None),
            DesignSpec::LatinHypercube { n, seed, axes } => {
                if *n == 0 {
                    return Err(DesignError(
                        "LatinHypercube: n = 0 (must satisfy n >= 1)".into(),
                    ));
                }
                (Kind::LatinHypercube, axes, Some((*n, *seed)))
            }
        };
        if axes.is_empty() {
            return Err(DesignError("the design has no axes".into()));
        }
        let axes: Vec<Axis> = axes
            .iter()
            .map(|a| resolve_axis(a, kind == Kind::LatinHypercube))
            .collect::<Result<_, _>>()
            .map_err(DesignError)?;
        for (k, a) in axes.iter().enumerate() {
            if axes[..k].iter().any(|b| b.path == a.path) {
                return Err(DesignError(format!("axis `{}` is given twice", a.path)));
            }
        }
        if kind == Kind::Zip {
            let n = axes[0].values.len();
            if let Some(a) = axes.iter().find(|a| a.values.len() != n) {
                return Err(DesignError(format!(
                    "Zip: axis `{}` has {} values, axis `{}` has {n}: a Zip needs axes of equal length",
                    a.path,
                    a.values.len(),
                    axes[0].path
                )));
            }
        }
        Ok(Design { kind, axes, sample })
    }

    /// The points, in order. Ids: Grid `g<i>_<j>...` (the value index on each axis), Zip
    /// `z<k>`, one-at-a-time `base` then `o<axis>_<k>`, Latin hypercube `s<k>`; indices
    /// zero-padded so that ids sort in design order.
    pub fn points(&self) -> Vec<DesignPoint> {
        let pad = |n: usize| n.saturating_sub(1).to_string().len();
        let axes = &self.axes;
        match self.kind {
            Kind::Grid => {
                let dims: Vec<usize> = axes.iter().map(|a| a.values.len()).collect();
                let total: usize = dims.iter().product();
                (0..total)
                    .map(|mut flat| {
                        // The last axis varies fastest.
                        let mut idx = vec![0; dims.len()];
                        for d in (0..dims.len()).rev() {
                            idx[d] = flat % dims[d];
                            flat /= dims[d];
                        }
                        let id = idx
                            .iter()
                            .zip(&dims)
                            .map(|(i, &n)| format!("{i:0w$}", w = pad(n)))
                            .collect::<Vec<_>>()
                            .join("_");
                        DesignPoint {
                            id: format!("g{id}"),
                            values: idx
                                .iter()
                                .zip(axes)
                                .map(|(&i, a)| Some(a.values[i].clone()))
                                .collect(),
                        }
                    })
                    .collect()
            }
            Kind::Zip => {
                let n = axes[0].values.len();
                (0..n)
                    .map(|k| DesignPoint {
                        id: format!("z{k:0w$}", w = pad(n)),
                        values: axes.iter().map(|a| Some(a.values[k].clone())).collect(),
                    })
                    .collect()
            }
            Kind::OneAtATime => {
                let mut out = vec![DesignPoint {
                    id: "base".into(),
                    values: vec![None; axes.len()],
                }];
                for (j, a) in axes.iter().enumerate() {
                    for (k, v) in a.values.iter().enumerate() {
                        let mut values = vec![None; axes.len()];
                        values[j] = Some(v.clone());
                        out.push(DesignPoint {
                            id: format!(
                                "o{j:0wa$}_{k:0wv$}",
                                wa = pad(axes.len()),
                                wv = pad(a.values.len())
                            ),
                            values,
                        });
                    }
                }
                out
            }
            Kind::LatinHypercube => {
                let (n, seed) = self.sample.unwrap_or((1, 0));
                let samples = latin_hypercube(n, axes.len(), seed);
                samples
                    .iter()
                    .enumerate()
                    .map(|(k, u)| DesignPoint {
                        id: format!("s{k:0w$}", w = pad(n)),
                        values: axes
                            .iter()
                            .zip(u)
                            .map(|(a, &u)| {
                                let i = a.interval.unwrap_or(Interval {
                                    start: 0.0,
                                    stop: 1.0,
                                    log: false,
                                });
                                let v = if i.log {
                                    (i.start.ln() + u * (i.stop.ln() - i.start.ln())).exp()
                                } else {
                                    i.start + u * (i.stop - i.start)
                                };
                                Some(fmt_number(v))
                            })
                            .collect(),
                    })
                    .collect()
            }
        }
    }
}

/// SplitMix64: a small, well-mixed generator; the same seed gives the same numbers on
/// every platform.
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n.
    fn below(&mut self, n: usize) -> usize {
        (self.unit() * n as f64) as usize % n.max(1)
    }
}

/// `n` points in the unit cube of dimension `dims`: in each dimension exactly one point
/// per stratum [k/n, (k+1)/n), placed at random within it.
pub fn latin_hypercube(n: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = SplitMix64(seed);
    let mut points = vec![vec![0.0; dims]; n];
    for d in 0..dims {
        let mut strata: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = rng.below(i + 1);
            strata.swap(i, j);
        }
        for (p, s) in points.iter_mut().zip(&strata) {
            p[d] = (*s as f64 + rng.unit()) / n as f64;
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(text: &str) -> Result<Design, String> {
        let spec: DesignSpec = ron::Options::default()
            .from_str(text)
            .map_err(|e| e.to_string())?;
        Design::from_spec(&spec).map_err(|e| e.to_string())
    }

    /// The design of `text`, which must be valid.
    fn valid(text: &str) -> Design {
        design(text).unwrap()
    }

    /// Why the design of `text` is refused.
    fn refused(text: &str) -> String {
        design(text).unwrap_err()
    }

    #[test]
    fn ranges_give_rounded_values() {
        let d = valid(r#"Grid([(path: "a.b", values: Range(start: 0.1, stop: 0.9, n: 5))])"#);
        assert_eq!(d.axes[0].values, ["0.1", "0.3", "0.5", "0.7", "0.9"]);
        let d = valid(r#"Grid([(path: "a", values: LogRange(start: 1e3, stop: 1e5, n: 3))])"#);
        assert_eq!(d.axes[0].values, ["1000.0", "10000.0", "100000.0"]);
        let d = valid(r#"Grid([(path: "a", values: [On, OffAfter(9.0), 4])])"#);
        assert_eq!(d.axes[0].values, ["On", "OffAfter(9.0)", "4"]);
        assert_eq!(fmt_number(4.0), "4.0");
        assert_eq!(fmt_number(1e-7), "0.0000001");
    }

    #[test]
    fn grid_zip_and_one_at_a_time_points() {
        let p = valid(
            r#"Grid([(path: "a", values: [1.0, 2.0]), (path: "b", values: Range(start: 0.0, stop: 10.0, n: 11))])"#,
        )
        .points();
        assert_eq!(p.len(), 22);
        assert_eq!(p[0].id, "g0_00");
        assert_eq!(p[12].id, "g1_01");
        assert_eq!(p[12].values, [Some("2.0".into()), Some("1.0".into())]);
        let d = valid(r#"Zip([(path: "a", values: [1.0, 2.0]), (path: "b", values: [3, 4])])"#);
        let p = d.points();
        assert_eq!(
            (p[1].id.as_str(), p[1].values.clone()),
            ("z1", vec![Some("2.0".into()), Some("4".into())])
        );
        let e = refused(r#"Zip([(path: "a", values: [1.0, 2.0]), (path: "b", values: [3])])"#);
        assert!(e.contains("equal length"), "{e}");
        let d = valid(r#"OneAtATime([(path: "a", values: [1.0, 2.0]), (path: "b", values: [3])])"#);
        let ids: Vec<_> = d.points().into_iter().map(|p| p.id).collect();
        assert_eq!(ids, ["base", "o0_0", "o0_1", "o1_0"]);
    }

    #[test]
    fn variant_axes_are_named_sets_of_overrides() {
        let d = valid(
            r#"Grid([
                (name: "reading", variants: [(name: "base"), (name: "unit", set: ["adhesion.direction=Unit", "adhesion.e_f=1.0"])]),
                (path: "materials.gamma", values: [0.1, 0.2]),
            ])"#,
        );
        assert_eq!(d.axes[0].path, "reading");
        assert_eq!(d.axes[0].values, ["base", "unit"]);
        assert!(d.axes[0].is_variants() && !d.axes[1].is_variants());
        assert_eq!(
            d.axes[0].variant_set("unit").unwrap(),
            ["adhesion.direction=Unit", "adhesion.e_f=1.0"]
        );
        assert_eq!(d.axes[0].variant_set("base").unwrap(), [] as [String; 0]);
        assert_eq!(d.axes[0].variant_set("other"), None);
        assert_eq!(d.axes[1].variant_set("0.1"), None);
        let p = d.points();
        assert_eq!(p.len(), 4);
        assert_eq!(p[2].id, "g1_0");
        assert_eq!(p[2].values, [Some("unit".into()), Some("0.1".into())]);
        // sweep.json keeps the sets (and an axis of values none).
        let json = serde_json::to_string(&d).unwrap();
        assert_eq!(json.matches("\"sets\"").count(), 1, "{json}");
        assert_eq!(serde_json::from_str::<Design>(&json).unwrap(), d);
        // Mistakes.
        assert!(
            refused(r#"Grid([(name: "r", variants: [(name: "a"), (name: "a")])])"#)
                .contains("given twice")
        );
        assert!(refused(r#"Grid([(name: "r", variants: [])])"#).contains("no variants"));
        assert!(refused(r#"Grid([(name: "r", variants: [(name: " ")])])"#).contains("not empty"));
        assert!(
            refused(r#"Grid([(name: "r", variants: [(name: "a", set: ["noequals"])])])"#)
                .contains("variant `a`")
        );
        assert!(
            refused(r#"Grid([(name: "r", path: "a.b", variants: [(name: "a")])])"#)
                .contains("an axis is")
        );
        assert!(refused(r#"Grid([(path: "a.b")])"#).contains("an axis is"));
        assert!(
            refused(
                r#"LatinHypercube(n: 2, seed: 1, axes: [(name: "r", variants: [(name: "a")])])"#
            )
            .contains("not variants")
        );
    }

    #[test]
    fn latin_hypercube_stratifies_each_axis_and_is_reproducible() {
        let d = valid(
            r#"LatinHypercube(n: 8, seed: 3, axes: [(path: "a", values: Range(start: 0.0, stop: 8.0)), (path: "b", values: LogRange(start: 1.0, stop: 100.0))])"#,
        );
        let p = d.points();
        assert_eq!(p.len(), 8);
        let mut strata: Vec<usize> = p
            .iter()
            .map(|q| q.values[0].as_ref().unwrap().parse::<f64>().unwrap() as usize)
            .collect();
        strata.sort();
        assert_eq!(strata, (0..8).collect::<Vec<_>>());
        assert_eq!(p, d.points());
        let e = refused(r#"LatinHypercube(n: 8, seed: 3, axes: [(path: "a", values: [1.0])])"#);
        assert!(e.contains("samples ranges"), "{e}");
        let e = refused(r#"Grid([(path: "a", values: Range(start: 0.0, stop: 1.0))])"#);
        assert!(e.contains("needs `n`"), "{e}");
        let e = refused(r#"Grid([(path: "a..b", values: [1])])"#);
        assert!(e.contains("not a field name"), "{e}");
    }
}
