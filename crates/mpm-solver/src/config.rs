//! Run settings: update scheme, time-step control, boundaries, small-mass threshold, objectivity.

use crate::error::SolverError;
use crate::math::{Real, Vector};
use mpm_contact::{Friction, Wall};
use serde::{Deserialize, Serialize};

pub use mpm_core::settings::{
    BadTimeStep, Contact, DEFAULT_COURANT, DEFAULT_SMALL_MASS_RATIO, MAX_COURANT, MassMatrix,
    Periodic, PicWeighting, STANDARD_GRAVITY, Scheme, SideWalls, TimeStep, Transfer,
};

/// Friction laws of the grid's boundary planes; `None` means no boundary there.
///
/// A scene without any boundary runs no contact stage at all.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Boundaries {
    /// The ground (terrain grid) or floor (regular grid): the bottom row of nodes.
    pub ground: Option<Friction>,
    /// The wall at the grid's first column.
    pub left_wall: Option<Friction>,
    /// The wall at the grid's last column.
    pub right_wall: Option<Friction>,
    /// The wall at the grid's first layer (z = z₀; 3D only).
    #[cfg(feature = "dim3")]
    #[serde(default)]
    pub back_wall: Option<Friction>,
    /// The wall at the grid's last layer (3D only).
    #[cfg(feature = "dim3")]
    #[serde(default)]
    pub front_wall: Option<Friction>,
}

impl Boundaries {
    /// true when at least one of the grid's sides is a boundary.
    pub fn any(&self) -> bool {
        #[cfg(feature = "dim3")]
        if self.back_wall.is_some() || self.front_wall.is_some() {
            return true;
        }
        self.ground.is_some() || self.left_wall.is_some() || self.right_wall.is_some()
    }

    /// every side of the grid with the same friction law (the ground, the walls).
    pub fn all(friction: Friction) -> Self {
        Self {
            ground: Some(friction),
            left_wall: Some(friction),
            right_wall: Some(friction),
            #[cfg(feature = "dim3")]
            back_wall: Some(friction),
            #[cfg(feature = "dim3")]
            front_wall: Some(friction),
        }
    }
}

/// Outflow faces: planes of the grid's sides through which material leaves the run. A particle
/// beyond one at the end of a step is taken out of the run, and the mass, momentum and energy
/// it carries out are booked ([`crate::Outflowed`], the energy ledger's `outflow`), so that the
/// residual stays closed; the run goes on. The nodes on an outflow face are free (no boundary
/// condition). A face is the plane x = `x_min` (material leaves towards −x), x = `x_max`
/// (+x), and in 3D z = `z_min`, z = `z_max`; `None` is no outflow there. The front end puts
/// them on the grid's sides; the solver takes any finite planes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Outflow {
    /// material at x < x_min leaves (m).
    pub x_min: Option<Real>,
    /// material at x > x_max leaves (m).
    pub x_max: Option<Real>,
    /// material at z < z_min leaves (m; 3D only).
    #[cfg(feature = "dim3")]
    #[serde(default)]
    pub z_min: Option<Real>,
    /// material at z > z_max leaves (m; 3D only).
    #[cfg(feature = "dim3")]
    #[serde(default)]
    pub z_max: Option<Real>,
}

impl Outflow {
    /// true when at least one face lets material leave.
    pub fn any(&self) -> bool {
        #[cfg(feature = "dim3")]
        if self.z_min.is_some() || self.z_max.is_some() {
            return true;
        }
        self.x_min.is_some() || self.x_max.is_some()
    }

    /// true when a particle at `x` has left through one of the faces.
    #[inline]
    pub fn has_left(&self, x: Vector) -> bool {
        let beyond = |lo: Option<Real>, hi: Option<Real>, c: Real| {
            lo.is_some_and(|l| c < l) || hi.is_some_and(|h| c > h)
        };
        #[cfg(feature = "dim3")]
        if beyond(self.z_min, self.z_max, x.z) {
            return true;
        }
        beyond(self.x_min, self.x_max, x.x)
    }

    /// the faces' coordinates with their names, for checks.
    fn planes(&self) -> Vec<(&'static str, Real)> {
        let mut v = Vec::new();
        let named = [("outflow.x_min", self.x_min), ("outflow.x_max", self.x_max)];
        v.extend(named.into_iter().filter_map(|(n, c)| c.map(|c| (n, c))));
        #[cfg(feature = "dim3")]
        {
            let named = [("outflow.z_min", self.z_min), ("outflow.z_max", self.z_max)];
            v.extend(named.into_iter().filter_map(|(n, c)| c.map(|c| (n, c))));
        }
        v
    }
}

/// Settings of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    /// Update scheme.
    pub scheme: Scheme,
    /// Time-step control.
    pub time_step: TimeStep,
    /// Gravitational acceleration (m/s²), (0, −9.81) by default.
    pub gravity: Vector,
    /// Boundary friction laws.
    pub boundaries: Boundaries,
    /// A periodic pair of sides in x (`None`: the sides are walls or open).
    #[serde(default)]
    pub periodic: Option<Periodic>,
    /// Faces of the grid's sides through which material leaves the run (none by default).
    #[serde(default)]
    pub outflow: Outflow,
    /// Walls anywhere, beside the grid's own sides: planes or segments at any position and angle
    /// (an inclined retaining wall, a check dam inside the domain). Under [`Contact::Surface`] a
    /// wall holds the nodes near it where material touches it, under [`Contact::Node`] the nodes
    /// on its face or inside its solid (see `stages/locate.rs`).
    #[serde(default)]
    pub walls: Vec<Wall>,
    /// Side walls across the plane of a plane-strain run (`None`: none, the paper's plane
    /// strain). In the loads ([`crate::Solver::boundary_loads`]) they follow the declared walls.
    #[cfg(not(feature = "dim3"))]
    #[serde(default)]
    pub side_walls: Option<SideWalls>,
    /// Nodes whose mass is below this fraction of the mean particle mass take no acceleration from
    /// internal force (the small-nodal-mass instability of §2(3)). Default 1e-4, which leaves
    /// MUSL and USAVG runs unchanged (their strains use remapped velocities). USL needs about 1e-2
    /// to survive cell crossings of a stressed body; values of several percent perturb the
    /// dynamics themselves (measured on a spinning square: see `tests/…/small_mass.rs`).
    pub small_mass_ratio: Real,
    /// Rotate stress (and tensor internal variables) with the material spin each step: an
    /// objective (Jaumann) stress rate integrated by exact incremental rotation (Hughes–Winget).
    pub objective_stress: bool,
    /// Gravity grows linearly from zero to its full value over this time (s); 0 applies it at
    /// once. A ramp a few times longer than the body's lowest natural period loads it quasi-
    /// statically, instead of dropping a stress-free body into an undamped elastic bounce.
    pub gravity_ramp: Real,
    /// Particle ↔ grid velocity transfer: FLIP (the paper's, default) or APIC.
    pub transfer: Transfer,
    /// Under FLIP, the share β of the PIC velocity in each particle's new velocity:
    /// v_p ← (1 − β)(v_p + Δt Σ_i S_ip a_i) + β Σ_i S_ip v_i^L (0: pure FLIP, eq 7; 1: PIC).
    /// FLIP alone never damps the particle velocities that the grid cannot see (its null
    /// space): a granular deposit keeps them for ever as kinetic energy that moves nothing, and
    /// they feed the few grains that touch a boundary alone until one is thrown (measured on the
    /// flume run to 60 s, `g2p.rs`). The blend removes a share β of that noise per step; what it
    /// takes is booked in the ledger as transfer dissipation. Scenes of granular materials get a
    /// non-zero default (mpm-scene); must be 0 with APIC, which damps that noise itself.
    #[serde(default)]
    pub pic_fraction: Real,
    /// Under FLIP, the PIC share given as a relaxation time τ (s) instead of per step: each step
    /// takes β = 1 − exp(−Δt/τ), so that the grid-invisible velocities decay as exp(−t/τ)
    /// whatever the time step (0: off, and [`SolverConfig::pic_fraction`] applies; the two are
    /// exclusive). A share per step damps at the rate β/Δt, which the Courant number and the
    /// stiffness set through Δt: a 3D column collapse ran 16 % farther at Courant 0.3 than at
    /// 0.1 with β = 0.001 per step (`docs/runout.md`).
    #[serde(default)]
    pub pic_relaxation: Real,
    /// How the PIC share is spread over the particles: the same share for every particle
    /// (default), or weighted by the share of each particle's velocity that the grid does not see
    /// ([`PicWeighting::Noise`]).
    #[serde(default)]
    pub pic_weighting: PicWeighting,
    /// A particle whose density has fallen below this fraction of its material's reference
    /// density (the lightest initial density of the material) counts as a separated grain: it
    /// carries no stress, and a compression first closes its gaps (its volume shrinks without
    /// stress) until it is back above the threshold, where it takes up load from zero (the
    /// disconnected state of Dunatunga & Kamrin 2015). 0 turns this off (elastic solids, the
    /// paper's cases). Drucker-Prager scenes get 0.5 by default (mpm-scene; μ(I) tracks its
    /// own opening and keeps 0): a sand packed at a solid fraction of 0.6, at half its density,
    /// is a cloud of grains at 0.3, far below any contact network. Without it, a lone grain resting on a boundary is squeezed by
    /// each step's contact and its elastic stress ratchets up (−122 kPa at 18 % of its density,
    /// measured on the flume) until it is thrown.
    #[serde(default)]
    pub separation_density: Real,
    /// When boundary planes hold their nodes: where material touches them (default) or always.
    pub contact: Contact,
    /// Lumped (the paper's, default) or consistent mass matrix.
    #[serde(default)]
    pub mass: MassMatrix,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            scheme: Scheme::default(),
            time_step: TimeStep::default(),
            gravity: Vector::NEG_Y * STANDARD_GRAVITY,
            boundaries: Boundaries::default(),
            periodic: None,
            outflow: Outflow::default(),
            walls: Vec::new(),
            #[cfg(not(feature = "dim3"))]
            side_walls: None,
            small_mass_ratio: DEFAULT_SMALL_MASS_RATIO,
            objective_stress: false,
            gravity_ramp: 0.0,
            transfer: Transfer::Flip,
            pic_fraction: 0.0,
            pic_relaxation: 0.0,
            pic_weighting: PicWeighting::Uniform,
            separation_density: 0.0,
            contact: Contact::Surface,
            mass: MassMatrix::Lumped,
        }
    }
}

impl SolverConfig {
    /// the PIC share β of a step of `dt`: [`SolverConfig::pic_fraction`], or with a
    /// [`SolverConfig::pic_relaxation`] τ, 1 − exp(−Δt/τ).
    pub fn pic_share(&self, dt: Real) -> Real {
        if self.pic_relaxation > 0.0 {
            -(-dt / self.pic_relaxation).exp_m1()
        } else {
            self.pic_fraction
        }
    }

    /// gravity at time `t` (s), after the ramp.
    pub fn gravity_at(&self, t: Real) -> Vector {
        if self.gravity_ramp > 0.0 {
            self.gravity * (t / self.gravity_ramp).min(1.0)
        } else {
            self.gravity
        }
    }

    /// the side walls of a plane-strain run (always `None` in 3D).
    #[inline(always)]
    pub fn side_walls(&self) -> Option<SideWalls> {
        #[cfg(not(feature = "dim3"))]
        return self.side_walls;
        #[cfg(feature = "dim3")]
        None
    }

    /// how many entries [`crate::Solver::boundary_loads`] has: the grid's sides, the declared
    /// walls, and the side walls when there are some.
    pub fn boundary_count(&self) -> usize {
        crate::SIDES + self.walls.len() + usize::from(self.side_walls().is_some())
    }

    /// checks every setting's range; the error names the setting, its value and the admissible range.
    pub fn validate(&self) -> Result<(), SolverError> {
        match self.time_step.checked() {
            Err(BadTimeStep::Courant(c)) => {
                return Err(SolverError::InvalidSetting {
                    name: "courant",
                    value: c,
                    expected: "0 < C ≤ 1 (explicit stability, eq 13); the paper advises 0.1",
                });
            }
            Err(BadTimeStep::Dt(dt)) => {
                return Err(SolverError::InvalidSetting {
                    name: "dt",
                    value: dt,
                    expected: "a positive, finite time step in seconds",
                });
            }
            Ok(_) => {}
        }
        if !self.gravity.is_finite() {
            return Err(SolverError::InvalidSetting {
                name: "gravity",
                value: if self.gravity.x.is_finite() { self.gravity.y } else { self.gravity.x },
                expected: "finite components (m/s²)",
            });
        }
        if !(self.gravity_ramp >= 0.0 && self.gravity_ramp.is_finite()) {
            return Err(SolverError::InvalidSetting {
                name: "gravity_ramp",
                value: self.gravity_ramp,
                expected: "a finite time ≥ 0 in seconds (0 applies gravity at once)",
            });
        }
        if !(self.small_mass_ratio >= 0.0 && self.small_mass_ratio < 1.0) {
            return Err(SolverError::InvalidSetting {
                name: "small_mass_ratio",
                value: self.small_mass_ratio,
                expected: "0 ≤ ratio < 1 (fraction of the mean particle mass)",
            });
        }
        if !(0.0..=1.0).contains(&self.pic_fraction) {
            return Err(SolverError::InvalidSetting {
                name: "pic_fraction",
                value: self.pic_fraction,
                expected: "0 ≤ pic_fraction ≤ 1 (0: FLIP, 1: PIC)",
            });
        }
        if !(0.0..1.0).contains(&self.separation_density) {
            return Err(SolverError::InvalidSetting {
                name: "separation_density",
                value: self.separation_density,
                expected: "0 ≤ separation_density < 1 (fraction of the reference density; 0: off)",
            });
        }
        if !(self.pic_relaxation >= 0.0 && self.pic_relaxation.is_finite()) {
            return Err(SolverError::InvalidSetting {
                name: "pic_relaxation",
                value: self.pic_relaxation,
                expected: "a finite time ≥ 0 in seconds (0: off)",
            });
        }
        if self.pic_relaxation > 0.0 && self.pic_fraction > 0.0 {
            return Err(SolverError::Incompatible {
                setting: "pic_relaxation",
                with: "pic_fraction",
                reason: "the PIC share is given either per step or as a relaxation time, not both",
            });
        }
        if (self.pic_fraction > 0.0 || self.pic_relaxation > 0.0) && self.transfer == Transfer::Apic
        {
            return Err(SolverError::Incompatible {
                setting: if self.pic_fraction > 0.0 { "pic_fraction" } else { "pic_relaxation" },
                with: "transfer",
                reason: "APIC damps grid-invisible noise itself: the PIC blend applies to FLIP",
            });
        }
        if let Some(w) = self.side_walls() {
            if !(w.width > 0.0 && w.width.is_finite()) {
                return Err(SolverError::InvalidSetting {
                    name: "side_walls.width",
                    value: w.width,
                    expected: "a positive, finite channel width (m)",
                });
            }
            if !(w.friction >= 0.0 && w.friction.is_finite()) {
                return Err(SolverError::InvalidSetting {
                    name: "side_walls.friction",
                    value: w.friction,
                    expected: "a finite friction coefficient ≥ 0",
                });
            }
        }
        if self.mass == MassMatrix::Consistent {
            let conflict = if cfg!(feature = "dim3") {
                Some(("dimension", "the 3D solver has the lumped mass matrix only: use `lumped`"))
            } else if self.transfer == Transfer::Apic {
                // APIC's affine matrix picks up velocity modes that the consistent projection
                // leaves to the gradients: a thrown sand block blew up within 6 steps (measured).
                Some(("transfer", "the consistent mass matrix is unstable with APIC: use FLIP"))
            } else if self.periodic.is_some() {
                Some(("periodic", "the consistent mass matrix does not fold periodic columns yet"))
            } else if self.side_walls().is_some() {
                // its reactions are formed from the final accelerations: the side walls'
                // friction would be booked a second time as a reaction.
                Some(("side_walls", "side walls act on the lumped mass matrix only: use `lumped`"))
            } else {
                None
            };
            if let Some((with, reason)) = conflict {
                return Err(SolverError::Incompatible { setting: "mass", with, reason });
            }
        }
        if let Some(p) = self.periodic {
            if p.columns < 4 {
                return Err(SolverError::InvalidSetting {
                    name: "periodic.columns",
                    value: f64::from(p.columns),
                    expected: "at least 4 cells between the periodic sides",
                });
            }
            if !(p.length > 0.0 && p.length.is_finite() && p.x_min.is_finite()) {
                return Err(SolverError::InvalidSetting {
                    name: "periodic.length",
                    value: p.length,
                    expected: "a positive, finite period (m) from a finite x_min",
                });
            }
            let b = self.boundaries;
            if b.left_wall.is_some() || b.right_wall.is_some() {
                return Err(SolverError::InvalidSetting {
                    name: "periodic",
                    value: p.length,
                    expected: "periodic sides without left or right walls",
                });
            }
            if !self.walls.is_empty() {
                return Err(SolverError::InvalidSetting {
                    name: "walls",
                    value: self.walls.len() as f64,
                    expected: "no walls beside periodic sides (not supported yet)",
                });
            }
        }
        if let Some((name, value)) = self.outflow.planes().into_iter().find(|(_, c)| !c.is_finite())
        {
            return Err(SolverError::InvalidSetting {
                name,
                value,
                expected: "a finite coordinate of the outflow face (m)",
            });
        }
        if let (Some(lo), Some(hi)) = (self.outflow.x_min, self.outflow.x_max)
            && lo >= hi
        {
            return Err(SolverError::InvalidSetting {
                name: "outflow.x_max",
                value: hi,
                expected: "an outflow face beyond x_min",
            });
        }
        #[cfg(feature = "dim3")]
        if let (Some(lo), Some(hi)) = (self.outflow.z_min, self.outflow.z_max)
            && lo >= hi
        {
            return Err(SolverError::InvalidSetting {
                name: "outflow.z_max",
                value: hi,
                expected: "an outflow face beyond z_min",
            });
        }
        if let Some(p) = self.periodic
            && (self.outflow.x_min.is_some() || self.outflow.x_max.is_some())
        {
            return Err(SolverError::InvalidSetting {
                name: "outflow",
                value: p.length,
                expected: "periodic sides without outflow faces along x",
            });
        }
        // (each boundary's loads are indexed by a u16: `loads.rs`)
        if self.walls.len() > usize::from(u16::MAX) - crate::SIDES - 1 {
            return Err(SolverError::InvalidSetting {
                name: "walls",
                value: self.walls.len() as f64,
                expected: "at most 65 000 walls",
            });
        }
        Ok(())
    }
}
