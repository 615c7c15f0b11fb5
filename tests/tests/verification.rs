//! Verification of the solver against analytic answers: the paper's cases (Abe et al. 2005) and the
//! standard MPM benchmarks. One module per source; each test is named after the case it reproduces.

mod verification {
    pub mod abe2005;
    pub mod bardenhagen2002;
    pub mod consistent_mass;
    pub mod floor;
    pub mod geostatic;
    pub mod guards;
    pub mod kinks;
    pub mod manufactured;
    pub mod objectivity;
    pub mod open_core;
    pub mod side_walls;
    pub mod small_mass;
    pub mod terrain3d;
    pub mod three_d;
}
