//! What the model reports, as the run's files record it: one row of `timeseries.csv`
//! ([`Observables`], what a scene reports at an output time, MODEL.md §7), the 3-D
//! columns after it ([`QuarterObservables`]), and the 3-D cell's state and mesh as its
//! state files and `mesh3.json` hold them ([`QuarterSnapshot`], [`QuarterMeshFile`]; the
//! unfolded quarter).
//!
//! The model fills them ([`crate::model::CellModel::observe`], `QuarterCell::snapshot`);
//! [`crate::run_files`] writes them into the run's files and reads them back. This module
//! owns the time series' format: the column names and order, a row's text, parsing a row
//! back, and interpolation between rows. A new column is added here once, to the `columns!` list
//! (which declares the field, [`COLUMNS`], [`Observables::values`] and
//! [`Observables::from_values`]) and to [`Observables::CSV_HEADER`], and every reader
//! follows.

use serde::{Deserialize, Serialize};

use crate::fem::Domain;
use crate::physics::{ActiveStrain, LatticeSubstrate};

/// Number of columns of `timeseries.csv`.
pub const N_COLUMNS: usize = 10;

/// The header of `timeseries.csv` before the paper's measures were added (cellsim before
/// `contact_radius_ref`, `strain_membrane` and `uy_nucleus_max`; its `strain_cytoplasm`
/// excluded the membrane). Recognised only to refuse such a file with a clear message.
pub const OLD_CSV_HEADER: &str =
    "t,contact_radius,uy_top,uy_centre,uy_bottom,strain_nucleus,strain_cytoplasm";

/// Declares [`Observables`] with one `f64` field per column of `timeseries.csv`, in column
/// order, together with [`COLUMNS`] and the conversions to and from a row of values, so
/// that the column list is written once.
macro_rules! columns {
    ($($(#[$doc:meta])* $field:ident,)*) => {
        /// The column names of `timeseries.csv`, in order.
        pub const COLUMNS: [&str; N_COLUMNS] = [$(stringify!($field)),*];

        /// The quantities of one output row, in the units of `timeseries.csv`.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
        pub struct Observables {
            $($(#[$doc])* pub $field: f64,)*
        }

        impl Observables {
            /// The values in CSV column order.
            pub fn values(&self) -> [f64; N_COLUMNS] {
                [$(self.$field),*]
            }

            /// The row whose values in CSV column order are `v` (inverse of [`Self::values`]).
            pub fn from_values(v: [f64; N_COLUMNS]) -> Self {
                let [$($field),*] = v;
                Observables { $($field),* }
            }
        }
    };
}

columns! {
    /// Time \[s\].
    t,
    /// Deformed length of the cell boundary within ε_ct of the substrate \[µm\] (half cell).
    contact_radius,
    /// Vertical displacement of the nucleus top p_t \[µm\] (negative = down).
    uy_top,
    /// Vertical displacement of the cell centre c \[µm\].
    uy_centre,
    /// Vertical displacement of the nucleus bottom p_b \[µm\].
    uy_bottom,
    /// Reference-area mean of ‖E‖_F over the nucleus (fraction).
    strain_nucleus,
    /// Reference-area mean of ‖E‖_F over the paper's cytoplasm, which includes the
    /// membrane (Sect. 2.1): cytoplasm and membrane together (fraction). Before the
    /// paper's measures were added this column was the cytoplasm without the membrane.
    strain_cytoplasm,
    /// Length along the reference contour of the part of the boundary in contact (the
    /// material of [`Self::contact_radius`]: same criterion, measured in the reference
    /// frame, as the paper's COMSOL does) \[µm\] (half cell).
    contact_radius_ref,
    /// Reference-area mean of ‖E‖_F over the membrane alone (fraction).
    strain_membrane,
    /// Largest downward displacement of the nucleus: the smallest u_y over every node
    /// (vertices and mid-side nodes) of the nucleus elements \[µm\] (negative = down, as
    /// `uy_top`; never above `uy_top` and `uy_bottom`, which are nucleus nodes).
    uy_nucleus_max,
}

impl Observables {
    /// The CSV header, exactly as the run writes it ([`COLUMNS`] joined by commas).
    pub const CSV_HEADER: &'static str = "t,contact_radius,uy_top,uy_centre,uy_bottom,\
         strain_nucleus,strain_cytoplasm,contact_radius_ref,strain_membrane,uy_nucleus_max";

    /// The value of column `name`, if it is one of [`COLUMNS`].
    pub fn get(&self, name: &str) -> Option<f64> {
        COLUMNS
            .iter()
            .position(|c| *c == name)
            .map(|k| self.values()[k])
    }

    /// Whether every value is finite (a run never writes NaN or infinity).
    pub fn is_finite(&self) -> bool {
        self.values().iter().all(|v| v.is_finite())
    }

    /// One CSV row (full precision).
    pub fn csv_row(&self) -> String {
        self.values().map(|v| v.to_string()).join(",")
    }

    /// Parses one CSV row (without its newline); the message says what is wrong.
    pub fn parse_csv_row(line: &str) -> Result<Self, RowError> {
        let v = parse_fields(line)?;
        let v: [f64; N_COLUMNS] = v.try_into().map_err(|v: Vec<f64>| RowError::Fields {
            found: v.len(),
            expected: N_COLUMNS,
        })?;
        Ok(Self::from_values(v))
    }
}

/// Why a line of timeseries.csv is not a row.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RowError {
    /// A field is not a number.
    #[error("`{0}` is not a number")]
    NotANumber(String),
    /// The line has another number of fields.
    #[error("{found} fields, expected {expected}")]
    Fields {
        /// Fields found.
        found: usize,
        /// Fields expected.
        expected: usize,
    },
    /// Fewer fields than the 2-D columns before the 3-D ones.
    #[error("fewer than {0} fields")]
    TooFew(usize),
}

/// The comma-separated numbers of a CSV line.
pub fn parse_fields(line: &str) -> Result<Vec<f64>, RowError> {
    line.split(',')
        .map(|f| {
            f.trim()
                .parse::<f64>()
                .map_err(|_| RowError::NotANumber(f.to_string()))
        })
        .collect()
}

/// The row of `rows` (sorted by time) at time `t`, linearly interpolated, or `None` when
/// `t` lies outside the rows (with a relative slack of 1e-9 of the last time).
pub fn interpolate(rows: &[Observables], t: f64) -> Option<Observables> {
    let first = rows.first()?;
    let last = rows.last()?;
    let slack = 1e-9 * last.t.abs().max(1.0);
    if t < first.t - slack || t > last.t + slack {
        return None;
    }
    let k = rows.partition_point(|o| o.t < t);
    if k == 0 {
        return Some(*first);
    }
    if k >= rows.len() {
        return Some(*last);
    }
    let (a, b) = (rows[k - 1], rows[k]);
    if (b.t - t).abs() <= slack {
        return Some(b);
    }
    let w = if b.t > a.t {
        (t - a.t) / (b.t - a.t)
    } else {
        1.0
    };
    let (va, vb) = (a.values(), b.values());
    let mut v: [f64; N_COLUMNS] = std::array::from_fn(|i| va[i] + w * (vb[i] - va[i]));
    v[0] = t;
    Some(Observables::from_values(v))
}

/// The 3-D quantities of one output row of a 3-D run (MODEL.md §10), written after the
/// 2-D columns of `timeseries.csv` ([`QuarterObservables::CSV_COLUMNS`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct QuarterObservables {
    /// Area of the cell surface in contact (depth > −ε_ct), deformed \[µm²\], whole cell.
    pub contact_area: f64,
    /// The same material surface measured on the reference sphere \[µm²\], whole cell.
    pub contact_area_ref: f64,
    /// √(A/π) of the deformed contact area \[µm\].
    pub contact_radius_equiv: f64,
    /// How far the nucleus bottom p_b went below the pillar tops \[µm\] (0 above them and on
    /// a flat substrate): max(0, y_top − (c_y − r_n + u_y(p_b))).
    pub penetration_depth: f64,
}

impl QuarterObservables {
    /// The 3-D columns, after [`Observables::CSV_HEADER`]'s.
    pub const CSV_COLUMNS: &'static str =
        "contact_area,contact_area_ref,contact_radius_equiv,penetration_depth";

    /// The values in column order.
    pub fn values(&self) -> [f64; 4] {
        [
            self.contact_area,
            self.contact_area_ref,
            self.contact_radius_equiv,
            self.penetration_depth,
        ]
    }

    /// Whether every value is finite.
    pub fn is_finite(&self) -> bool {
        self.values().iter().all(|v| v.is_finite())
    }
}

/// What the mesh file of a 3-D run (`mesh3.json`) records: the quarter cell's ten-node
/// tetrahedra and its outer surface, with what the figures draw beside it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct QuarterMeshFile {
    /// Reference node coordinates \[µm\].
    pub nodes: Vec<[f64; 3]>,
    /// Ten-node tetrahedra (gmsh's node order, [`crate::fem::tet10`]).
    pub elements: Vec<[usize; 10]>,
    /// Domain of each element.
    pub domains: Vec<Domain>,
    /// Six-node triangles of the outer sphere r = r_c (the quarter's cell surface).
    pub outer_faces: Vec<[usize; 6]>,
    /// The substrate in 3-D.
    pub substrate: LatticeSubstrate,
    /// Active strain regions, if any.
    pub active: Option<ActiveStrain>,
    /// Contact band half-width ε_ct \[µm\].
    pub contact_eps: f64,
    /// Fibronectin layer thickness e_f \[µm\], with adhesion.
    pub layer_thickness: Option<f64>,
    /// Cell centre \[µm\].
    pub center: [f64; 3],
    /// Phase end times T_g0, T_as0, T_a0 and the end time \[s\].
    pub phase_times: [f64; 4],
}

/// The state of the cell at one output time, `D` components per node: the half cell's
/// ([`Snapshot`], `D = 2`) or the 3-D cell's ([`QuarterSnapshot`], `D = 3`: the
/// `state_<phase>.json` of a 3-D run, and what a VTU frame or a figure is drawn from).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "[f64; D]: Serialize",
    deserialize = "[f64; D]: Deserialize<'de>"
))]
pub struct SnapshotOf<const D: usize> {
    /// Time \[s\].
    pub t: f64,
    /// Displacement of every node \[µm\].
    pub u: Vec<[f64; D]>,
    /// Velocity of every node \[µm/s\]: the v unknowns with inertia, u̇ without.
    pub v: Vec<[f64; D]>,
    /// μ_as per node [pN/µm³] (`None` off the membrane or without adhesion).
    pub mu_as: Vec<Option<f64>>,
    /// Per element: reference-area (2-D) or reference-volume (3-D) mean of ‖E‖_F.
    pub element_strain: Vec<f64>,
    /// Per element: reference-area (2-D) or reference-volume (3-D) mean of det F.
    pub element_jacobian: Vec<f64>,
}

/// The state of the half cell at one output time.
pub type Snapshot = SnapshotOf<2>;

/// The state of the 3-D cell at one output time.
pub type QuarterSnapshot = SnapshotOf<3>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_the_columns_joined() {
        assert_eq!(Observables::CSV_HEADER, COLUMNS.join(","));
        // The original columns keep their order: the new ones come after them.
        assert!(Observables::CSV_HEADER.starts_with(&format!("{OLD_CSV_HEADER},")));
    }

    #[test]
    fn a_row_round_trips_through_its_text() {
        let v: [f64; N_COLUMNS] = std::array::from_fn(|i| (i as f64 + 0.1) * -1.7e-3);
        let o = Observables::from_values(v);
        assert_eq!(o.values(), v);
        assert_eq!(Observables::parse_csv_row(&o.csv_row()), Ok(o));
        assert_eq!(o.get("uy_top"), Some(v[2]));
        // The paper's measures, after the original columns, by name.
        assert_eq!(o.get("contact_radius_ref"), Some(v[7]));
        assert_eq!(o.get("strain_membrane"), Some(v[8]));
        assert_eq!(o.get("uy_nucleus_max"), Some(v[9]));
        assert_eq!(o.get("nope"), None);
        let err = Observables::parse_csv_row("1,2,3").unwrap_err();
        assert_eq!(err.to_string(), "3 fields, expected 10");
        let err = Observables::parse_csv_row("1,2,x,4,5,6,7").unwrap_err();
        assert_eq!(err.to_string(), "`x` is not a number");
    }

    #[test]
    fn interpolation_is_linear_between_rows_and_none_outside() {
        let a = Observables::from_values([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        let b = Observables::from_values([10.0, 3.0, 2.0, 1.0, 0.0, -1.0, -2.0, 1.0, 0.0, 1.0]);
        let m = interpolate(&[a, b], 2.5).unwrap();
        assert_eq!(
            m.values(),
            [2.5, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.5, 6.0, 7.0]
        );
        assert_eq!(interpolate(&[a, b], 10.0), Some(b));
        assert_eq!(interpolate(&[a, b], 10.1), None);
        assert_eq!(interpolate(&[a, b], -0.1), None);
    }
}
