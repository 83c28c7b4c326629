//! Parameter checks shared by the error model and the RANSAC tracker; each error names the
//! field.

/// A failed check: the field and what is wrong.
pub(crate) type FieldError = (String, String);

/// Every value is a finite number above zero.
pub(crate) fn positive(fields: &[(&str, f64)]) -> Result<(), FieldError> {
    for &(name, v) in fields {
        if !(v.is_finite() && v > 0.0) {
            return Err((name.into(), format!("must be a positive number, got {v}")));
        }
    }
    Ok(())
}

/// Every value is a finite number, zero or above.
pub(crate) fn non_negative(fields: &[(&str, f64)]) -> Result<(), FieldError> {
    for &(name, v) in fields {
        if !(v.is_finite() && v >= 0.0) {
            return Err((
                name.into(),
                format!("must be a non-negative number, got {v}"),
            ));
        }
    }
    Ok(())
}

/// Every value lies in `[0, max]`.
pub(crate) fn unit_range(fields: &[(&str, f64, f64)]) -> Result<(), FieldError> {
    for &(name, v, max) in fields {
        if !(v.is_finite() && (0.0..=max).contains(&v)) {
            return Err((name.into(), format!("must be in [0, {max}], got {v}")));
        }
    }
    Ok(())
}
