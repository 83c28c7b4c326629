//! The columns of `subtrajectories.csv`, the one table both its writer and its readers
//! know: the session folder writes and reads it ([`crate::Session::save`]) and a venue
//! contribution reads the uploaded copy ([`crate::venue::Contribution::from_files`]).

use crate::ErrorUnit;

pub(crate) const HEADER: &str = "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class";

/// The header of a session whose results are in degrees: the error column is `error_deg`.
pub(crate) fn header(unit: ErrorUnit) -> String {
    HEADER.replace(",error_m,", &format!(",{},", unit.error_key()))
}
