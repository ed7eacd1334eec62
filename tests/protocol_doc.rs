//! docs/protocol.md is kept true by the code: every message's `field` module (row, offset, type,
//! name) against its layout table, the `Params` table against the parameter declaration
//! (`vpf::params`), and the payload lengths of §4 against the code's.

use vpf::link::layout::Field;
use vpf::link::{belief, control, mission, report, sensors, PARAMS_LEN};
use vpf::params::{Kind, ParamId, Params, Range};

const DOC: &str = include_str!("../docs/protocol.md");

/// The table rows (cells, trimmed) of the section headed `### {title}`, up to the next heading,
/// whose first cell is a row number.
fn rows(title: &str) -> Vec<Vec<String>> {
    let start = DOC
        .find(&format!("\n### {title}"))
        .unwrap_or_else(|| panic!("no section {title}"));
    let body = &DOC[start + 1..];
    let end = body[4..].find("\n#").map_or(body.len(), |e| e + 4);
    body[..end]
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect::<Vec<_>>()
        })
        .filter(|c| c[0].parse::<u8>().is_ok())
        .collect()
}

fn check_fields(title: &str, fields: &[Field]) {
    let doc = rows(title);
    let ours: Vec<[String; 4]> = fields
        .iter()
        .map(|f| {
            [
                f.row.to_string(),
                format!("{}{}", f.offset, f.plus),
                f.ty.to_string(),
                f.name.to_string(),
            ]
        })
        .collect();
    let theirs: Vec<[String; 4]> = doc
        .iter()
        .map(|c| {
            let name = c[3].split_whitespace().next().unwrap_or("").to_string();
            [c[0].clone(), c[1].clone(), c[2].clone(), name]
        })
        .collect();
    assert_eq!(
        ours, theirs,
        "{title}: the field module and docs/protocol.md differ"
    );
}

#[test]
fn every_message_layout_matches_the_document() {
    check_fields("Nav (0x01)", sensors::field::nav::ALL);
    check_fields("Scanline (0x02)", sensors::field::scanline::ALL);
    check_fields("Contacts (0x03)", sensors::field::contacts::ALL);
    check_fields("Mission (0x04)", control::field::mission::ALL);
    check_fields("ChartObstacle (0x05)", control::field::chart_obstacle::ALL);
    check_fields("ChartClear (0x06)", control::field::chart_clear::ALL);
    check_fields("Tick (0x08)", control::field::tick::ALL);
    check_fields("MissionCount (0x09)", mission::field::mission_count::ALL);
    check_fields("MissionItem (0x0A)", mission::field::mission_item::ALL);
    check_fields("Survey (0x0B)", mission::field::survey::ALL);
    check_fields("Command (0x81)", report::field::command::ALL);
    check_fields("Telemetry (0x82)", report::field::telemetry::ALL);
    check_fields("Reply (0x83)", report::field::reply::ALL);
    check_fields("Log (0x84)", report::field::log::ALL);
    check_fields("Belief (0x85)", belief::field::ALL);
}

/// The Params table as the declaration gives it: row, offset, type, parameter, unit, range,
/// default.
fn params_table() -> Vec<[String; 7]> {
    let d = Params::default();
    let mut offset = 0;
    ParamId::ALL
        .iter()
        .map(|&id| {
            let (ty, range) = match id.kind() {
                Kind::F32 => ("f32", id.range().to_string()),
                Kind::U8 => ("u8", id.range().to_string()),
                Kind::U32 => ("u32", id.range().to_string()),
                Kind::Code(names) => (
                    "u8",
                    names
                        .iter()
                        .enumerate()
                        .map(|(i, n)| format!("{i} {n}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                ),
            };
            let default = match (id.kind(), d.get(id)) {
                (Kind::Code(names), vpf::params::Value::Code(c)) => names[c as usize].to_string(),
                (_, v) => v.to_string(),
            };
            let row = [
                id.index().to_string(),
                offset.to_string(),
                ty.to_string(),
                id.name().to_string(),
                id.unit().to_string(),
                range,
                default,
            ];
            offset += id.kind().wire_len();
            row
        })
        .collect()
}

#[test]
fn the_params_table_is_the_declaration() {
    let ours = params_table();
    let theirs: Vec<Vec<String>> = rows("Params (0x07)");
    let expected = ours
        .iter()
        .map(|r| format!("| {} |", r.join(" | ")))
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(
        ours.iter().map(|r| r.to_vec()).collect::<Vec<_>>(),
        theirs,
        "docs/protocol.md's Params table differs from the declaration in src/params; it \
         should read:\n{expected}"
    );
    // §4's payload length.
    assert!(
        DOC.contains(&format!(
            "| 0x07 | [`Params`](#params-0x07)             | host → firmware | {PARAMS_LEN}"
        )),
        "§4 must give Params' length, {PARAMS_LEN}"
    );
    assert!(DOC.contains(&format!("whole parameter set, {PARAMS_LEN} bytes")));
    // A range that names another parameter names a declared one.
    for id in ParamId::ALL {
        if let Range::UpTo(_, other) = id.range() {
            assert!(ParamId::ALL.contains(&other));
        }
    }
}

/// hil/scenarios/README.md's `[planner]` table lists every parameter but `period_s` (the
/// scenario's `dt_s`), with the declared unit and default.
#[test]
fn the_scenario_schema_lists_every_parameter() {
    let readme = include_str!("../hil/scenarios/README.md");
    let start = readme.find("### `[planner]`").expect("a [planner] section");
    let readme = &readme[start..];
    let readme = &readme[..readme[4..].find("\n### ").map_or(readme.len(), |e| e + 4)];
    let d = Params::default();
    for id in ParamId::ALL.into_iter().filter(|&i| i != ParamId::period_s) {
        let row = readme
            .lines()
            .find(|l| l.starts_with(&format!("| `{}` |", id.name())))
            .unwrap_or_else(|| panic!("hil/scenarios/README.md has no row for {}", id.name()));
        let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
        assert_eq!(cells[2], id.unit(), "{}: unit", id.name());
        let listed = cells[3];
        match (id.kind(), d.get(id)) {
            (Kind::Code(names), vpf::params::Value::Code(c)) => {
                assert_eq!(
                    listed,
                    format!("`\"{}\"`", names[c as usize]),
                    "{}",
                    id.name()
                )
            }
            (_, v) => {
                // The README may round (0.628 for 0.2π): the leading number within 0.1 %.
                let n: f32 = listed
                    .split_whitespace()
                    .next()
                    .and_then(|t| t.parse().ok())
                    .unwrap_or_else(|| panic!("{}: default {listed} is not a number", id.name()));
                let want = v.as_f32();
                assert!(
                    (n - want).abs() <= 1e-3 * want.abs().max(1.0),
                    "{}: default {listed} in the README, {want} declared",
                    id.name()
                );
            }
        }
    }
}
