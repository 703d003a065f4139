//! A picture's view direction and size limits, shared by `render`, `plot` and the snapshots
//! (`output.snapshot_view`, `output.snapshot_size`).

use crate::math::Real;

/// The largest picture side, in pixels, that `render` and `plot` draw (a render's supersampled
/// buffers at 8192 × 8192 take about 1.9 GB).
pub const MAX_SIDE: usize = 8192;

/// The azimuth and elevation (degrees) of a view: `iso`, `top`, `bottom`, `front`, `back`,
/// `side`, or `AZIMUTH,ELEVATION` with the elevation in [−90, 90]. The error quotes the view.
pub fn angles(spec: &str) -> Result<(Real, Real), String> {
    Ok(match spec {
        "iso" => (-60.0, 20.0),
        "top" => (-90.0, 90.0),
        "bottom" => (-90.0, -90.0),
        "front" => (-90.0, 0.0),
        "back" => (90.0, 0.0),
        "side" => (0.0, 0.0),
        other => {
            let (a, e) = other.split_once(',').ok_or_else(|| {
                format!(
                    "--view '{other}': use iso, top, bottom, front, back, side, or \
                     AZIMUTH,ELEVATION in degrees (e.g. 30,20)"
                )
            })?;
            let a: Real = a
                .trim()
                .parse()
                .map_err(|_| format!("--view '{other}': azimuth '{a}' is not a number"))?;
            let e: Real = e
                .trim()
                .parse()
                .map_err(|_| format!("--view '{other}': elevation '{e}' is not a number"))?;
            if !(a.is_finite() && (-90.0..=90.0).contains(&e)) {
                return Err(format!(
                    "--view '{other}': the elevation must lie in [-90, 90] degrees"
                ));
            }
            (a, e)
        }
    })
}
