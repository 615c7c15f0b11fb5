//! The grid's side faces as the flow meets them: which faces that the scene did not declare a
//! boundary (no wall law, not `"outflow"`) the material came within a cell of, when first, how
//! high it stood there and how much of it was there at once.
//!
//! Such a face is the edge of the calculation, not of the world: material that crosses it
//! stops the run, and a flow that presses against it has been shaped by where the grid ends.
//! A run reports it (`summary.json` `edges`, a warning in its last lines) so that a map shaped
//! by an artificial edge is not handed on as a result. Outflow faces are reported by what left
//! through them (`summary.json` `outflow`).
//!
//! The watch is taken at each series row; it works on plain coordinates so that 2D and 3D runs
//! share it (in 2D the faces are at x only and z is 0).

use serde::{Deserialize, Serialize};

/// One watched face: the plane where coordinate `axis` (0 = x, 2 = z) equals `at`, with the
/// material on the side opposite to `outward` (−1: the face at the low end, +1: the high end).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaceWatch {
    /// the face's key in `[boundaries]` (`left_wall`, `right_wall`, `back_wall`, `front_wall`).
    pub name: String,
    /// the coordinate across the face: 0 = x, 2 = z.
    pub axis: usize,
    /// where the face is along it (m).
    pub at: f64,
    /// −1 for a face at the low end of the axis, +1 at the high end.
    pub outward: f64,
    /// when material first came within reach of it (s).
    pub first_time: Option<f64>,
    /// the largest flow height seen within reach: the highest particle top above the ground
    /// under it (m).
    pub max_flow_height: f64,
    /// the largest mass within reach at one series row (kg; kg/m in plane strain).
    pub max_mass: f64,
}

/// The faces of a run that the scene did not declare, watched at each series row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeWatch {
    /// how near a particle must come to count as at the face (m): one cell.
    pub reach: f64,
    /// the watched faces.
    pub faces: Vec<FaceWatch>,
}

/// One particle as the watch sees it.
#[derive(Clone, Copy, Debug)]
pub struct Grain {
    /// its position (x, y, z) (m; z = 0 in 2D).
    pub position: [f64; 3],
    /// the ground's height under it (m).
    pub ground: f64,
    /// its mass.
    pub mass: f64,
}

/// A face the material reached (`summary.json` `edges`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeContact {
    /// the face's key in `[boundaries]`.
    pub face: String,
    /// when material first came within a cell of it (s).
    pub first_time: f64,
    /// the largest flow height there (m).
    pub max_flow_height: f64,
    /// the largest mass there at one time (kg; kg/m in plane strain).
    pub max_mass: f64,
    /// that mass as a fraction of the run's material.
    pub max_mass_fraction: f64,
}

impl EdgeContact {
    /// the warning a run's last lines and `summary.json` `warnings` carry.
    pub fn warning(&self) -> String {
        format!(
            "material reached the grid's undeclared side `{}` at t = {:.3} s (up to {:.3} m \
             high there, {:.1} % of the mass within a cell of it at once): the grid's edge, not \
             the terrain, shaped the flow there (material crossing it stops the run); declare \
             the side `\"outflow\"` to let it leave, a wall if one stands there, or widen the \
             grid",
            self.face,
            self.first_time,
            self.max_flow_height,
            100.0 * self.max_mass_fraction
        )
    }
}

impl EdgeWatch {
    /// a watch over `faces` (name, axis, at, outward) with the given reach; `None` without a
    /// face to watch.
    pub fn new(faces: Vec<(&str, usize, f64, f64)>, reach: f64) -> Option<Self> {
        if faces.is_empty() {
            return None;
        }
        let faces = faces
            .into_iter()
            .map(|(name, axis, at, outward)| FaceWatch {
                name: name.to_string(),
                axis,
                at,
                outward,
                first_time: None,
                max_flow_height: 0.0,
                max_mass: 0.0,
            })
            .collect();
        Some(Self { reach, faces })
    }

    /// takes the particles at time `t` into the watch; `top` is how far a particle's top
    /// stands above its centre (half the particle spacing).
    pub fn observe(&mut self, t: f64, grains: &[Grain], top: f64) {
        for face in &mut self.faces {
            let mut mass = 0.0;
            let mut height: f64 = 0.0;
            for g in grains {
                // distance inside the face (positive: inside the grid)
                let inside = face.outward * (face.at - g.position[face.axis]);
                if inside <= self.reach {
                    mass += g.mass;
                    height = height.max(g.position[1] + top - g.ground);
                }
            }
            if mass > 0.0 {
                face.first_time.get_or_insert(t);
                face.max_mass = face.max_mass.max(mass);
                face.max_flow_height = face.max_flow_height.max(height);
            }
        }
    }

    /// the faces the material reached, with their masses against `total_mass`.
    pub fn reached(&self, total_mass: f64) -> Vec<EdgeContact> {
        self.faces
            .iter()
            .filter_map(|f| {
                Some(EdgeContact {
                    face: f.name.clone(),
                    first_time: f.first_time?,
                    max_flow_height: f.max_flow_height,
                    max_mass: f.max_mass,
                    max_mass_fraction: if total_mass > 0.0 { f.max_mass / total_mass } else { 0.0 },
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three grains, one within a cell of the right face (x = 10, reach 1): only that face is
    /// reached, at the first time it is seen, with its mass and its top above the ground; a
    /// later row with more mass there raises the mass but keeps the first time.
    #[test]
    fn a_face_is_reached_by_the_grains_within_a_cell_of_it() {
        let mut w =
            EdgeWatch::new(vec![("left_wall", 0, 0.0, -1.0), ("right_wall", 0, 10.0, 1.0)], 1.0)
                .unwrap();
        let grain = |x: f64, y: f64, mass: f64| Grain { position: [x, y, 0.0], ground: 1.0, mass };
        let row = [grain(5.0, 1.5, 1.0), grain(8.9, 1.5, 1.0), grain(9.2, 3.0, 2.0)];
        w.observe(0.5, &row, 0.25);
        let later = [grain(9.5, 1.5, 1.0), grain(9.2, 2.0, 2.0)];
        w.observe(1.0, &later, 0.25);
        let reached = w.reached(4.0);
        assert_eq!(reached.len(), 1, "{reached:?}");
        let r = &reached[0];
        assert_eq!((r.face.as_str(), r.first_time), ("right_wall", 0.5));
        assert_eq!((r.max_mass, r.max_mass_fraction), (3.0, 0.75));
        assert_eq!(r.max_flow_height, 3.0 + 0.25 - 1.0);
        assert!(r.warning().contains("`right_wall` at t = 0.500 s"), "{}", r.warning());
    }
}
