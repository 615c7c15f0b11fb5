//! Named cases with exact answers: the ground normal at a kink, a 10 km domain holding a 1 m²
//! body, wall treatment of the 9-node stencils, and every kind of bad input.

mod bad_input;
mod boundaries;
mod extent;
mod kinks;
