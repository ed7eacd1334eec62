//! `trajectory_<vehicle>.csv`: one row per sample.
//!
//! Columns (SI units, angles in radians, Earth frame with ψ counter-clockwise from +x):
//! `t_s, x_m, y_m, heading_rad, u_mps, v_mps, r_radps, vx_mps, vy_mps, psi_cmd_rad,
//! speed_cmd_mps, mode, ghost_depth, target_x_m, target_y_m, nearest_m, thrust`.
//! Numbers use Rust's shortest round-trip form (`NaN` where the data had one); `mode` is quoted
//! only if it holds a comma, quote or line break.

use std::path::Path;

use crate::types::VehicleRecord;

/// The header line (without the newline).
pub const HEADER: &str = "t_s,x_m,y_m,heading_rad,u_mps,v_mps,r_radps,vx_mps,vy_mps,psi_cmd_rad,\
speed_cmd_mps,mode,ghost_depth,target_x_m,target_y_m,nearest_m,thrust";

/// Writes the vehicle's samples as CSV to `path`.
pub fn write_csv(path: &Path, v: &VehicleRecord) -> std::io::Result<()> {
    let mut w = writer(std::fs::File::create(path)?);
    write_rows(&mut w, v)?;
    w.flush()
}

/// The CSV text: header and one row per sample.
pub fn to_csv(v: &VehicleRecord) -> String {
    let mut w = writer(Vec::with_capacity(64 + v.samples.len() * 160));
    // Writing to memory cannot fail.
    let _ = write_rows(&mut w, v);
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// RFC 4180 quoting only where needed, `\n` line ends.
fn writer<W: std::io::Write>(w: W) -> csv::Writer<W> {
    csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(w)
}

fn write_rows<W: std::io::Write>(w: &mut csv::Writer<W>, v: &VehicleRecord) -> csv::Result<()> {
    w.write_record(HEADER.split(','))?;
    for s in &v.samples {
        let st = &s.state;
        let nums = [
            s.t,
            st.position.x,
            st.position.y,
            st.heading,
            st.u,
            st.v,
            st.r,
            st.velocity.x,
            st.velocity.y,
            s.psi_cmd,
            s.speed_cmd,
        ];
        for x in nums {
            w.write_field(x.to_string())?;
        }
        w.write_field(&s.mode)?;
        w.write_field(s.ghost_depth.to_string())?;
        w.write_field(s.target.x.to_string())?;
        w.write_field(s.target.y.to_string())?;
        w.write_field(s.nearest_m.to_string())?;
        w.write_field(st.thrust.to_string())?;
        w.write_record(None::<&[u8]>)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::test_support::sample;

    #[test]
    fn header_and_one_row_per_sample_with_matching_columns() {
        let mut s1 = sample(0.5, 1.0, 2.0, 3.0);
        s1.mode = "Hold(a, \"b\")".into();
        let v = VehicleRecord {
            samples: vec![sample(0.0, 0.0, 0.0, 1.0), s1],
            ..VehicleRecord::default()
        };
        let csv = to_csv(&v);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0].split(',').count(), 17);
        assert_eq!(lines[1].split(',').count(), 17);
        assert!(lines[1].starts_with("0,0,0,0.3,0.5,"));
        assert!(lines[2].contains(",\"Hold(a, \"\"b\"\")\","));
        assert!(lines[2].ends_with(",10,0,3,2"));
    }

    #[test]
    fn empty_record_gives_the_header_only() {
        assert_eq!(to_csv(&VehicleRecord::default()), format!("{HEADER}\n"));
    }
}
