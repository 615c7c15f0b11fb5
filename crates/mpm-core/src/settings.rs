//! The run settings that do not depend on dimension: the update scheme, the velocity transfer and
//! its PIC share's weighting, the contact rule, the mass matrix, the time-step control and its
//! bounds, the periodic sides and the side walls of plane strain. The settings that do (gravity,
//! the grid's boundary planes, walls, outflow faces) are the solver's, which holds these in its
//! `SolverConfig` and checks their ranges.

use serde::{Deserialize, Serialize};

/// Floating-point type of every quantity (SI units).
pub type Real = f64;

/// The order in which a step updates stress relative to the grid solve (SPEC §1, paper §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Update Stress Last (Sulsky et al. 1995): strain from the Lagrangian nodal velocity v^L.
    Usl,
    /// Modified USL (Sulsky et al.): strain from nodal velocities remapped from the updated
    /// particles (eq 8), the paper's §2 algorithm.
    Musl,
    /// Update Stress First (Bardenhagen 2002): strain and stress from the P2G velocities, before
    /// the forces are computed.
    Usf,
    /// Update Stress Averaged (Nairn 2003): a USF-type update over Δt/2 at the start and a
    /// MUSL-type update over Δt/2 at the end. The paper's choice for its energy behaviour.
    #[default]
    Usavg,
}

impl Scheme {
    /// every scheme, in the paper's order of presentation.
    pub const ALL: [Scheme; 4] = [Scheme::Usl, Scheme::Musl, Scheme::Usf, Scheme::Usavg];

    /// the scheme's usual name.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Usl => "USL",
            Scheme::Musl => "MUSL",
            Scheme::Usf => "USF",
            Scheme::Usavg => "USAVG",
        }
    }
}

/// How velocity travels between particles and grid (beyond the paper, which uses FLIP).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Transfer {
    /// The paper's transfer: nodes get Σ m_p v_p S_ip / m_i, particles add Σ a_i S_ip Δt to their
    /// velocity (eq 7). Keeps fine detail, but a node beside a free edge sees only the particles
    /// on one side, so a rotating body gets spurious strain there.
    #[default]
    Flip,
    /// Affine particle-in-cell (Jiang et al. 2015): each particle also carries an affine velocity
    /// matrix C_p and contributes m_p (v_p + C_p (x_i − x_p)) S_ip to node i; after the grid solve
    /// v_p = Σ v_i^L S_ip and C_p = Σ v_i^L ⊗ G_ip. Reproduces any linear velocity field exactly on
    /// the grid (rigid rotation carries no spurious strain) at the cost of 32 bytes per particle;
    /// damps grid-scale noise like PIC but keeps rotation.
    Apic,
}

impl Transfer {
    /// the transfer's usual name.
    pub fn name(self) -> &'static str {
        match self {
            Transfer::Flip => "FLIP",
            Transfer::Apic => "APIC",
        }
    }
}

/// How the FLIP update's PIC share β (the solver settings' `pic_fraction`) is spread over the
/// particles (beyond the paper, which has no PIC share).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PicWeighting {
    /// every particle takes the share β.
    #[default]
    Uniform,
    /// particle p takes β w_p, w_p = |n|² / (|n|² + |v^PIC|²), where v^PIC = Σ_i S_ip v_i^L is the
    /// velocity the grid sees at the particle and n = v^FLIP − v^PIC the part it does not see:
    /// the full share where a particle's velocity is all noise (a deposit whose grid velocity is
    /// nil, where the share is what brings it to rest), little where the particle moves with
    /// the grid's field (a flowing mass, where a uniform share acts as a viscosity of the order
    /// of β Δx²/Δt and shortens the runout: measured in `docs/runout.md`). A grain alone on its
    /// nodes is all seen, though, so the grains a flow throws keep their speed: not the default.
    Noise,
}

impl PicWeighting {
    /// the scene file's keyword.
    pub fn name(self) -> &'static str {
        match self {
            PicWeighting::Uniform => "uniform",
            PicWeighting::Noise => "noise",
        }
    }
}

/// The mass matrix of the grid solve (beyond the paper, which lumps it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MassMatrix {
    /// The paper's: m_i = Σ_p m_p S_ip on the diagonal, a_i = f_i / m_i (eq 4). Cheap and robust,
    /// but the lumped transfer smooths the particles' velocity field (numerical dissipation).
    #[default]
    Lumped,
    /// M_ij = Σ_p m_p S_ip S_jp (with a 5 % lumped share that keeps it regular: see
    /// the solver's mass stage), solved by conjugate gradients for the accelerations and, as an L2
    /// projection, for the particle-to-grid and remapped velocities. Less dissipation at a
    /// solve per transfer.
    Consistent,
}

impl MassMatrix {
    /// the scene file's keyword.
    pub fn name(self) -> &'static str {
        match self {
            MassMatrix::Lumped => "lumped",
            MassMatrix::Consistent => "consistent",
        }
    }
}

/// When a node on a boundary plane is held by the plane (beyond the paper, which holds every such
/// node).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Contact {
    /// A node on a plane is held only while material touches the plane there: some particle of
    /// the node's support, within half its own size of the plane, or reaching it within the step
    /// (the displacement check NairnMPM adds to contact detection). The normal velocity the plane
    /// imposes then reaches those particles as in PIC (their normal velocity relaxes towards the
    /// plane's by S_ip) rather than as a FLIP increment, so that a held node cannot feed energy
    /// back through particles whose velocity it only partly corrected. A body lands where its
    /// surface meets the plane, and friction acts only on material that touches it.
    /// `Fixed` planes hold their nodes always.
    #[default]
    Surface,
    /// The paper's rule (§2(4)): every node on a plane is held, whatever the gap between the
    /// material and the plane, and the impulse reaches the particles as a FLIP increment. A body
    /// is stopped up to one cell above the plane, and a block dropped on a frictionless floor
    /// gains 12–13 % energy at C = 0.1 under MUSL, USF and USAVG (first order in Δt).
    Node,
}

/// How the time step Δt is chosen (eq 13: Δt ≤ L/c).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeStep {
    /// Δt = C·L / max_p(c_p + |v_p|) every step, with Courant number C in (0, 1].
    Courant(Real),
    /// A fixed Δt (s); every step checks that its Courant number stays ≤ 1.
    Fixed(Real),
}

/// The paper's advice, Δt ≈ 0.1 L/c (§2(4)): the Courant number a scene gets by default.
pub const DEFAULT_COURANT: Real = 0.1;

/// The explicit scheme's stability bound on the Courant number (eq 13): the scene's Courant
/// number, a fixed Δt's, the true Courant number Δt·s̃_p/L of every particle with its true
/// signal s̃_p (the solver's time-step stage) and a step's displacement in cells are all
/// held to it.
pub const MAX_COURANT: Real = 1.0;

/// Nodes lighter than this fraction of the mean particle mass take body force only (§2(3)): the
/// default of the solver settings' `small_mass_ratio`.
pub const DEFAULT_SMALL_MASS_RATIO: Real = 1e-4;

impl TimeStep {
    /// the time step if its number is in range: a Courant number in (0, [`MAX_COURANT`]], a
    /// fixed Δt positive and finite. The one check of these bounds: the solver's settings and
    /// the scene's `[solver]` table both call it and word its answer for their reader.
    pub fn checked(self) -> Result<Self, BadTimeStep> {
        match self {
            TimeStep::Courant(c) if !(c > 0.0 && c <= MAX_COURANT) => Err(BadTimeStep::Courant(c)),
            TimeStep::Fixed(dt) if !(dt > 0.0 && dt.is_finite()) => Err(BadTimeStep::Dt(dt)),
            ok => Ok(ok),
        }
    }
}

/// A time step out of range ([`TimeStep::checked`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BadTimeStep {
    /// a Courant number outside (0, [`MAX_COURANT`]] (eq 13).
    Courant(Real),
    /// a fixed Δt that is not positive and finite (s).
    Dt(Real),
}

impl Default for TimeStep {
    /// [`DEFAULT_COURANT`].
    fn default() -> Self {
        TimeStep::Courant(DEFAULT_COURANT)
    }
}

/// A periodic pair of sides: the grid's columns of nodes `i` and `i + columns` are one column
/// (their sums are shared), and a particle leaving through one side enters through the other,
/// `length` = `columns` cells further. The other sides keep their boundaries; the paired sides
/// can have none.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Periodic {
    /// x of the left side (m).
    pub x_min: Real,
    /// cells between the two sides (≥ 4, so that no stencil reaches a column twice).
    pub columns: u32,
    /// distance between the two sides (m): `columns` cell widths.
    pub length: Real,
}

/// The friction of two parallel side walls a distance `width` apart across the plane of a
/// plane-strain run (a flume or channel of that width): each acts on the material with the
/// traction `friction · |σ_zz|` against its in-plane velocity, a body force
/// `2 friction |σ_zz| / width` per unit volume, applied at the nodes so that it stops a node
/// but never reverses it (the solver's side-wall stage). Only compressive `σ_zz` presses on the
/// walls. Plane strain only: in 3D the walls are faces of the grid or declared walls.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SideWalls {
    /// the channel's width between the walls (m), > 0.
    pub width: Real,
    /// the walls' Coulomb friction coefficient μ_w = tan δ, ≥ 0.
    pub friction: Real,
}

/// Standard gravity g (m/s²).
pub const STANDARD_GRAVITY: Real = 9.81;
