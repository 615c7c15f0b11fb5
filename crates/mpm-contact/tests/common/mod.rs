//! Independent references shared by the test binaries: the paper's acceleration form and a brute-force
//! projection onto the admissible cone of a corner.
//!
//! Written from the equations, not from the crate's code, so that agreement means something.

#![allow(dead_code)]

use mpm_contact::Vector;

/// standard gravity used by the paper's examples, m/s².
pub const G: f64 = 9.81;

/// gravity as a vector, −y.
pub fn gravity() -> Vector {
    Vector::new(0.0, -G)
}

/// unit vector at `angle` radians from +x.
pub fn unit(angle: f64) -> Vector {
    Vector::new(angle.cos(), angle.sin())
}

/// The paper's acceleration form (eqs 14–17) for a node with v_n = 0 on a boundary of inward normal `n`
/// and coefficient `mu`, with the no-reversal rule of SPEC §3: returns (a^c, v^L).
///
/// Contact if a·n < 0 (eq 14, inward normal). If v_t ≠ 0 the tangential acceleration is decreased by
/// μ|a_n| along −sign(v_t) (eqs 15–16 with μ' = μ); if that would reverse v_t within the step the node
/// sticks (a_t = −v_t/Δt). If v_t = 0, μ' = |a_t|/|a_n| caps at μ: the friction cancels a_t up to μ|a_n|.
/// The normal component of the acceleration is removed (eq 17).
pub fn paper_acceleration_form(
    n: Vector,
    mu: f64,
    v: Vector,
    a: Vector,
    dt: f64,
) -> (Vector, Vector) {
    let a_n = a.dot(n);
    if a_n >= 0.0 {
        return (a, v + a * dt);
    }
    // n × (a × n) in 2D: the tangential part of a, as a vector.
    let a_tan = a - a_n * n;
    let v_tan = v - v.dot(n) * n;
    let friction = mu * a_n.abs();
    if v_tan.length() > 0.0 {
        let dir = v_tan.normalize();
        let candidate = a_tan - friction * dir;
        let v_end = v_tan + candidate * dt;
        if v_end.dot(dir) <= 0.0 { (-v_tan / dt, Vector::ZERO) } else { (candidate, v_end) }
    } else if a_tan.length() <= friction {
        (Vector::ZERO, v_tan)
    } else {
        let candidate = a_tan - friction * a_tan.normalize();
        (candidate, v_tan + candidate * dt)
    }
}

/// The Euclidean projection of `w` onto the cone {u : u·n_k ≥ 0 for every k}, by brute force over the
/// cone's boundary rays (each ray lies on some line u·n_k = 0 and satisfies every constraint).
pub fn project_onto_cone(normals: &[Vector], w: Vector) -> Vector {
    let admissible = |u: Vector| normals.iter().all(|n| u.dot(*n) >= -1e-14 * u.length());
    if admissible(w) {
        return w;
    }
    let mut best = Vector::ZERO;
    for n in normals {
        for ray in [Vector::new(n.y, -n.x), Vector::new(-n.y, n.x)] {
            if !admissible(ray) {
                continue;
            }
            let candidate = w.dot(ray).max(0.0) * ray;
            if (candidate - w).length() < (best - w).length() {
                best = candidate;
            }
        }
    }
    best
}
