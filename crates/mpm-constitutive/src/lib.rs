//! Small-strain constitutive models for geomaterials: linear elasticity, Drucker-Prager with
//! non-associated flow and Prager mixed hardening, and the μ(I) rheology of dense granular flow,
//! integrated one strain increment at a time.
//!
//! This crate implements §6 of Abe, Johansson & Konagai (2005), "Dry sand flow analysis with
//! MPM" (eq 10–11: elastic increment; eqs 23–25: Drucker-Prager yield function, plastic potential
//! and flow rule), on full 3D symmetric tensors so that 2D (plane strain: `Δε_zz = Δε_yz =
//! Δε_zx = 0`, `σ_zz` carried) and 3D codes can both use it. It knows nothing of grids or
//! particles: a solver calls [`ConstitutiveModel::update`] once per material point and step, or,
//! in plane strain, [`ConstitutiveModel::update_plane`] on the four components that remain
//! ([`PlaneTensor`]), which gives the same bits at two thirds of the work.
//!
//! # Glossary
//! - `σ` stress, `ε` strain ([`SymTensor`], storage `[xx, yy, zz, xy, yz, zx]`, tensor shear
//!   components: `ε_xy = γ_xy/2`), `I1 = tr σ`, `J2 = ½ dev σ : dev σ`.
//! - `K`, `G`, `E`, `ν` elastic moduli ([`LinearElastic`]).
//! - `α`, `αg`, `k`, `β`, `H`, `M`, `Δλ`, `ε̄ᵖ`: Drucker-Prager friction and dilatancy
//!   coefficients, cone size, back stress, plastic modulus, mixing parameter, plastic multiplier
//!   and equivalent plastic strain ([`DruckerPrager`]).
//!
//! Sign convention: **tension positive** (compression has negative stress and strain).
//! Units: SI (Pa, J/m³, kg/m³, m/s); angles in degrees in parameter structs.
//!
//! # Map
//! - [`tensor`]: [`SymTensor`], the 6×6 [`Tangent`] convention, [`PlaneTensor`] and
//!   [`Symmetric`], the arithmetic the return mappings are written against once for both.
//! - [`elastic`]: [`LinearElastic`] (eq 10), wave speeds for the time step (eq 13).
//! - [`model`]: the [`ConstitutiveModel`] trait a solver uses, [`UpdateReport`], [`Branch`],
//!   and [`TangentModel`].
//! - [`drucker_prager`]: [`DruckerPrager`] (eqs 23–25) with the cone/apex return mapping and
//!   its consistent tangent.
//! - [`mohr_coulomb`]: [`MohrCoulomb`], the pyramid of `(c, φ, ψ)` with no cone to choose, its
//!   exact return in principal stresses (face, edge, apex), consistent tangent and softening;
//!   [`principal`]: the principal decomposition it is written in.
//! - [`mu_i`]: [`MuI`], the μ(I) rheology of dense granular flow (Jop, Forterre & Pouliquen
//!   2006) as an elasto-viscoplastic, rate-dependent model that separates in tension.
//! - [`element_test`]: single-point drivers with mixed stress/strain control (§6(3)).
//!
//! # Example: a plane-strain uniaxial compression test
//! ```
//! use mpm_constitutive::element_test::uniaxial_plane_strain;
//! use mpm_constitutive::{ConeMatch, DruckerPrager, DruckerPragerParams, SymTensor};
//!
//! let sand = DruckerPrager::new(DruckerPragerParams {
//!     young: 2.0e6,
//!     poisson: 0.3,
//!     cohesion: 10.0,
//!     friction_angle_deg: 40.0,
//!     dilatancy_angle_deg: 0.0,
//!     hardening_modulus: 0.0,
//!     mixing: 1.0,
//!     cone_match: ConeMatch::PlaneStrain,
//! })?;
//! // compress to ε_yy = −1e-3 in 400 steps with σ_xx = 0 and ε_zz = 0.
//! let path = uniaxial_plane_strain(&sand, SymTensor::ZERO, -1.0e-3, 400)?;
//! let first_yield = path.iter().find(|p| p.branch == "cone").unwrap();
//! let last = path.last().unwrap();
//! assert!(first_yield.stress.yy < -28.0 && first_yield.stress.yy > -29.5);
//! // perfectly plastic, non-dilatant: the steady state of the paper's element test.
//! assert!((last.stress.yy - -36.15).abs() < 0.01);
//! assert!(last.stress.xx.abs() < 1e-6);
//! assert!(last.eps_p_bar > 0.0);
//! # Ok::<(), mpm_constitutive::ConstitutiveError>(())
//! ```

pub mod drucker_prager;
pub mod elastic;
pub mod element_test;
pub mod error;
pub mod model;
pub mod mohr_coulomb;
pub mod mu_i;
pub mod principal;
pub mod tensor;

pub use drucker_prager::{
    ConeMatch, DpBranch, DpPerfectState, DpState, DpVariables, DruckerPrager, DruckerPragerParams,
};
pub use elastic::LinearElastic;
pub use error::ConstitutiveError;
pub use model::{Branch, ConstitutiveModel, MAX_BRANCHES, TangentModel, UpdateReport};
pub use mohr_coulomb::{McBranch, McState, MohrCoulomb, MohrCoulombParams, MohrCoulombSoftening};
pub use mu_i::{MuI, MuIBranch, MuIParams, MuIState};
pub use tensor::{PlaneTensor, SymTensor, Symmetric, Tangent};
