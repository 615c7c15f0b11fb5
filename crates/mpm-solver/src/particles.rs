//! Material points stored as a struct of arrays.
//!
//! Glossary: p particle index; m_p mass (kg per metre of thickness); V_p volume (m³ per metre, i.e. the
//! area the point stands for); ρ_p = m_p / V_p density; x_p position; v_p velocity; σ_p Cauchy stress,
//! **tension positive**, the four components plane strain leaves (σ_zz carried, σ_yz = σ_zx = 0).
//! Each array has one entry per particle; index p refers to the same particle in every array.

use crate::math::{Matrix, Real, Stress, Vector};
use serde::{Deserialize, Serialize};

/// All particles of a scene. `S` is the constitutive model's internal state (`()` for elasticity).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Particles<S> {
    /// Current position x_p (m).
    pub position: Vec<Vector>,
    /// Current velocity v_p (m/s).
    pub velocity: Vec<Vector>,
    /// Mass m_p (kg per metre of thickness); constant.
    pub mass: Vec<Real>,
    /// Current volume V_p (m² per metre of thickness), updated by eq 12.
    pub volume: Vec<Real>,
    /// Cauchy stress σ_p (Pa, tension positive; `[xx, yy, zz, xy]`).
    pub stress: Vec<Stress>,
    /// Constitutive internal variables.
    pub state: Vec<S>,
    /// Index into the solver's material list.
    pub material: Vec<u16>,
    /// Body the particle was generated in (for output and runout metrics).
    pub body: Vec<u16>,
    /// Position at generation, for displacement output.
    pub initial_position: Vec<Vector>,
    /// Affine velocity matrix C_p (1/s) of the APIC transfer; empty under FLIP (which pays
    /// nothing for it). Column-major `glam` matrix: C_p · r is the velocity offset at r.
    #[serde(default)]
    pub affine: Vec<Matrix>,
    /// With periodic sides, the x each particle's wraps took off its position so far: its
    /// position had it never wrapped is x + `unwrap` (the runout measures of an endless slope
    /// follow it). Empty (and free) without periodic sides.
    #[serde(default)]
    pub unwrap: Vec<Real>,
}

impl<S> Default for Particles<S> {
    fn default() -> Self {
        Self {
            position: Vec::new(),
            velocity: Vec::new(),
            mass: Vec::new(),
            volume: Vec::new(),
            stress: Vec::new(),
            state: Vec::new(),
            material: Vec::new(),
            body: Vec::new(),
            initial_position: Vec::new(),
            affine: Vec::new(),
            unwrap: Vec::new(),
        }
    }
}

/// What a new particle starts with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewParticle<S> {
    /// Position (m).
    pub position: Vector,
    /// Velocity (m/s).
    pub velocity: Vector,
    /// Volume (m² per metre).
    pub volume: Real,
    /// Density (kg/m³).
    pub density: Real,
    /// Initial stress (Pa, tension positive).
    pub stress: Stress,
    /// Initial internal state.
    pub state: S,
    /// Material index.
    pub material: u16,
    /// Body index.
    pub body: u16,
}

impl<S> NewParticle<S> {
    /// a stress-free particle of material 0 and body 0 (the usual start of a single-material
    /// scene).
    pub fn unstressed(
        position: Vector,
        velocity: Vector,
        volume: Real,
        density: Real,
        state: S,
    ) -> Self {
        Self {
            position,
            velocity,
            volume,
            density,
            stress: Stress::ZERO,
            state,
            material: 0,
            body: 0,
        }
    }
}

impl<S> Particles<S> {
    /// an empty set with room for `n` particles.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            position: Vec::with_capacity(n),
            velocity: Vec::with_capacity(n),
            mass: Vec::with_capacity(n),
            volume: Vec::with_capacity(n),
            stress: Vec::with_capacity(n),
            state: Vec::with_capacity(n),
            material: Vec::with_capacity(n),
            body: Vec::with_capacity(n),
            initial_position: Vec::with_capacity(n),
            affine: Vec::new(),
            unwrap: Vec::new(),
        }
    }

    /// number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// true when there is no particle.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// appends one particle; its mass is ρ V.
    pub fn push(&mut self, p: NewParticle<S>) {
        self.position.push(p.position);
        self.velocity.push(p.velocity);
        self.mass.push(p.density * p.volume);
        self.volume.push(p.volume);
        self.stress.push(p.stress);
        self.state.push(p.state);
        self.material.push(p.material);
        self.body.push(p.body);
        self.initial_position.push(p.position);
    }

    /// particle `p`'s position had it never wrapped through periodic sides (its position
    /// without them).
    pub fn unwrapped_position(&self, p: usize) -> Vector {
        let mut x = self.position[p];
        if let Some(u) = self.unwrap.get(p) {
            x.x += u;
        }
        x
    }

    /// density ρ_p = m_p / V_p of particle `p` (kg/m³).
    pub fn density(&self, p: usize) -> Real {
        self.mass[p] / self.volume[p]
    }

    /// total mass Σ m_p (kg per metre).
    pub fn total_mass(&self) -> Real {
        self.mass.iter().sum()
    }

    /// total linear momentum Σ m_p v_p.
    pub fn momentum(&self) -> Vector {
        self.mass.iter().zip(&self.velocity).map(|(&m, &v)| m * v).sum()
    }

    /// keeps the particles p whose `keep[p]` is true, in their order, in every array (and in
    /// `extra`, an array of the caller's with one entry per particle, or empty); returns how many
    /// were removed. A `keep` of another length than the particles' changes nothing.
    pub fn retain<T>(&mut self, keep: &[bool], extra: &mut Vec<T>) -> usize {
        let n = self.len();
        let mask = keep;
        fn filter<T>(v: &mut Vec<T>, mask: &[bool]) {
            if v.len() == mask.len() {
                let mut k = 0;
                v.retain(|_| {
                    k += 1;
                    mask[k - 1]
                });
            }
        }
        filter(&mut self.position, mask);
        filter(&mut self.velocity, mask);
        filter(&mut self.mass, mask);
        filter(&mut self.volume, mask);
        filter(&mut self.stress, mask);
        filter(&mut self.state, mask);
        filter(&mut self.material, mask);
        filter(&mut self.body, mask);
        filter(&mut self.initial_position, mask);
        filter(&mut self.affine, mask);
        filter(&mut self.unwrap, mask);
        filter(extra, mask);
        n - self.len()
    }

    /// the arrays' lengths agree (a set built by `push` always satisfies this; `affine` may also
    /// be empty).
    pub fn is_consistent(&self) -> bool {
        let n = self.len();
        if !(self.affine.is_empty() || self.affine.len() == n) {
            return false;
        }
        if !(self.unwrap.is_empty() || self.unwrap.len() == n) {
            return false;
        }
        [
            self.velocity.len(),
            self.mass.len(),
            self.volume.len(),
            self.stress.len(),
            self.state.len(),
            self.material.len(),
            self.body.len(),
            self.initial_position.len(),
        ]
        .iter()
        .all(|&l| l == n)
    }
}
