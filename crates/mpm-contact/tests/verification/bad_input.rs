//! Bad input: typed errors at construction naming the boundary, and no panic from a bad step.

use mpm_contact::{
    Boundary, ContactError, ContactStatus, Friction, Vector, apply_all, try_apply_all,
};

use crate::common::gravity;

const MU: Friction = Friction::Coulomb { mu: 0.3 };

#[test]
fn zero_non_finite_or_non_unit_normals_are_refused() {
    assert!(matches!(Boundary::new(Vector::ZERO, MU), Err(ContactError::ZeroNormal { .. })));
    for bad in [
        Vector::new(f64::NAN, 1.0),
        Vector::new(0.0, f64::INFINITY),
        Vector::new(f64::NEG_INFINITY, 0.0),
    ] {
        assert!(
            matches!(Boundary::new(bad, MU), Err(ContactError::NonFiniteNormal { .. })),
            "{bad}"
        );
    }
    for bad in [Vector::new(1.0, 1.0), Vector::new(1.0 + 2e-9, 0.0), Vector::new(0.0, 1e-3)] {
        match Boundary::new(bad, MU) {
            Err(ContactError::NonUnitNormal { normal, length }) => {
                assert_eq!(normal, bad);
                assert_eq!(length, bad.length());
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
    // Within 1e-9 of unit length: accepted and renormalised.
    let b = Boundary::new(Vector::new(0.0, 1.0 + 5e-10), MU).unwrap();
    assert_eq!(b.normal(), Vector::Y);
}

#[test]
fn negative_or_non_finite_friction_is_refused() {
    for mu in [-0.1, f64::NAN, f64::INFINITY, -f64::INFINITY] {
        match Boundary::new(Vector::Y, Friction::Coulomb { mu }) {
            Err(ContactError::InvalidFrictionCoefficient { normal, mu: got }) => {
                assert_eq!(normal, Vector::Y);
                assert!(got.to_bits() == mu.to_bits());
            }
            other => panic!("μ = {mu}: {other:?}"),
        }
    }
    for angle in [-1.0, 90.0, 120.0, f64::NAN] {
        assert!(matches!(
            Boundary::with_friction_angle_deg(Vector::Y, angle),
            Err(ContactError::InvalidFrictionAngle { .. })
        ));
    }
    // A valid angle gives μ = tan(angle); a bad normal is still caught.
    let b = Boundary::with_friction_angle_deg(Vector::Y, 27.0).unwrap();
    assert_eq!(b.friction(), Friction::Coulomb { mu: 27f64.to_radians().tan() });
    assert!(Boundary::with_friction_angle_deg(Vector::ZERO, 27.0).is_err());
}

#[test]
fn error_messages_name_the_boundary_and_the_offending_value() {
    let message = Boundary::new(Vector::new(1.0, 1.0), MU).unwrap_err().to_string();
    assert!(message.contains("normal [1, 1]") && message.contains("1.414"), "{message}");
    let message = Boundary::new(Vector::X, Friction::Coulomb { mu: -0.5 }).unwrap_err().to_string();
    assert!(message.contains("normal [1, 0]") && message.contains("-0.5"), "{message}");
}

#[test]
fn a_bad_step_is_reported_by_try_apply_and_passed_through_by_apply() {
    let b = Boundary::new(Vector::Y, MU).unwrap();
    let v = Vector::new(1.0, 0.0);
    for dt in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            b.try_apply(1.0, v, gravity(), dt),
            Err(ContactError::InvalidTimeStep { .. })
        ));
        assert!(matches!(
            try_apply_all(&[b], 1.0, v, gravity(), dt),
            Err(ContactError::InvalidTimeStep { .. })
        ));
        let out = b.apply(1.0, v, gravity(), dt);
        assert_eq!(out.status, ContactStatus::Separating);
        assert_eq!(out.acceleration, gravity());
        assert_eq!(apply_all(&[b], 1.0, v, gravity(), dt).status, ContactStatus::Separating);
    }
    for mass in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            b.try_apply(mass, v, gravity(), 1e-3),
            Err(ContactError::InvalidMass { .. })
        ));
        // apply still constrains the kinematics, and reports zero work rather than nonsense.
        let out = b.apply(mass, v, gravity(), 1e-3);
        assert_eq!(out.status, ContactStatus::Sliding);
        assert_eq!((out.friction_work, out.normal_work), (0.0, 0.0));
    }
    let nan = Vector::new(f64::NAN, 0.0);
    assert!(matches!(
        b.try_apply(1.0, nan, gravity(), 1e-3),
        Err(ContactError::NonFiniteState { .. })
    ));
    assert!(matches!(b.try_apply(1.0, v, nan, 1e-3), Err(ContactError::NonFiniteState { .. })));
    // Non-finite state does not panic anywhere.
    for friction in [MU, Friction::Rough, Friction::Fixed] {
        let b = Boundary::new(Vector::Y, friction).unwrap();
        let _ = b.apply(1.0, nan, gravity(), 1e-3);
        let _ = b.constrain_velocity(nan);
        let _ = apply_all(&[b, b], 1.0, v, nan, 1e-3);
    }
    // A valid step through try_apply equals apply.
    assert_eq!(b.try_apply(1.0, v, gravity(), 1e-3).unwrap(), b.apply(1.0, v, gravity(), 1e-3));
}

#[test]
fn deserialising_validates_like_new() {
    let b = Boundary::new(Vector::new(0.6, 0.8), Friction::Coulomb { mu: 0.5 }).unwrap();
    let text = serde_json::to_string(&b).unwrap();
    assert_eq!(serde_json::from_str::<Boundary>(&text).unwrap(), b);
    let rough: Boundary =
        serde_json::from_str(r#"{"normal":[0.0,1.0],"friction":"Rough"}"#).unwrap();
    assert_eq!(rough.friction(), Friction::Rough);
    for bad in [
        r#"{"normal":[1.0,1.0],"friction":"Rough"}"#,
        r#"{"normal":[0.0,0.0],"friction":"Fixed"}"#,
        r#"{"normal":[0.0,1.0],"friction":{"Coulomb":{"mu":-1.0}}}"#,
    ] {
        let err = serde_json::from_str::<Boundary>(bad).unwrap_err().to_string();
        assert!(err.contains("boundary with normal"), "{bad}: {err}");
    }
}
