//! The guard: the last line between the planner and the thrusters. Before a command goes out it
//! is checked against what the vehicle believes — the obstacle table, the other vehicles and
//! the evidence map's cells — independently of the potential field. A command whose motion
//! would take the hull into something believed is turned away, slowed or stopped, and says so
//! ([`Mode::Guarded`], counted in telemetry). The field stays the planner; this is the
//! all-stop of MOOS-IvP and the stop/back-up of ArduPilot's avoidance, not a second planner.
//! None of the seeds has it; seed 000 relies on the field alone, which is only as good as the
//! perception and the tuning.
//!
//! **The check.** A motion along heading θ at speed v sweeps the segment from the vehicle's
//! position p to p + L·(cos θ, sin θ), L = v·T + v²/2b + `margin_m`: what the vehicle
//! covers during the reaction time T (one period: the command takes effect next period), then
//! braking at b (`Params::brake`: `brake_mps2`, by default F_max, the most the planner itself
//! commands), plus a margin. The motion is
//! *blocked* when, somewhere along the segment, the clearance (signed distance to the nearest
//! believed surface) falls below the hull radius (`Params::agent_radius_m`, and a margin:
//! [`GuardConfig::hull_margin`]) **and** below the
//! clearance the vehicle has now — so a vehicle already closer than its hull to a wall may still
//! move away from it or along it, never closer.
//!
//! **The verdict**, in order:
//! 1. the vehicle's present motion (its measured velocity, within its braking distance) is
//!    blocked → **stop**: v_set = 0, the planner's heading kept (the vehicle turns while it
//!    brakes; a slow-turning craft creeping slower than [`STILL_MPS`] is at rest here);
//! 2. the commanded motion is clear → the command goes out unchanged;
//! 3. a heading within ±`max_turn_rad` of the commanded one, tried nearest first in steps of
//!    `turn_step_rad`, is clear at the commanded speed → **turn** to it;
//! 4. a lower speed (halving down to `min_speed`) is clear on the commanded heading → **slow**;
//! 5. otherwise → **stop** (a craft that turns slowly turns on the spot meanwhile, towards
//!    the planner's target: [`turn_on_the_spot`]).
//!
//! **A craft that turns slowly** (`Params::turn_rate_rps` > 0, e.g. the flat-fish AUV of seed 003
//! at ≈ 0.046 rad/s, a 22 m turning radius at 1 m/s) does not go where it is told but where it
//! points: it keeps its heading ψ and turns towards θ at most at that rate while it covers the
//! same reaction and braking distance, at the larger of the commanded and the present speed
//! (it cannot slow at once either). The segment is then the arc it sweeps, as a polyline of
//! [`ARC_SEGMENTS`] chords (each sampled at its time's midpoint) and the margin straight on, and
//! stopping (step 1 below) is braking along the arc it turns on meanwhile. Headings beyond the
//! turn it can make before it stops all sweep the same, hardest, arc: for such a craft the
//! guard's choices are the turns it can make, slower, or a stop. Against movers (below) such a
//! craft is judged on its course over the horizon ([`Helm::course`]: the heading turning at
//! its rate, the speed changing at F_max or its braking), not on the velocity it is told:
//! held to "turn away north at once", the flat-fish was judged clear of a mover that met it
//! while it was still turning. With the rate 0 (the default) the check is the straight
//! segment above, unchanged.
//!
//! **Skid.** Such a craft also slides sideways coming out of a turn: the flat-fish skids
//! outward at 5–8 cm/s, and its sway damps out over seconds, about as long as it takes to
//! stop. The arc carries the sideways speed measured now, turning with the heading, the whole
//! way to the stop (it damps out slower than the surge: at 0.1 m/s of surge the flat-fish
//! still skids at 4 cm/s). Without it the guard stopped it a braking distance from a rock
//! ahead and the skid took it the rest of the way: with perfect perception (`hil bench
//! --sensing contacts`) it touched still structure in 7 of the 102 clutter, box and wall-gap
//! worlds of seeds 0–33, by a few millimetres; with it, none (and 88 → 92 successes). Held
//! out, seeds 34–101, with channels and harbours: contacts 14 → 0, successes 277 → 283 of
//! 340. With its own sonar, seeds 0–169, within chance: at `--trial 1` 1 781 → 1 783 of
//! 2 040 and contacts 8 → 7 (crossing 1, 16 and 141 gone; a channel wall seen late and a
//! head-on new); at trial 0 1 792 → 1 783 and 2 → 4 (crossing 114 gone; a channel, a U-trap
//! and a formation new, grazes of 1 cm). Movers are judged on [`Helm::course`] without it: with
//! it, crossing and head-on at trial 1 turned over 11 contacts for 8 → 7.
//!
//! **Movers** (obstacles and other vehicles with a velocity) are judged by their closest point
//! of approach instead: each is carried from its last sighting to now on its velocity, and a
//! motion is blocked when, held for [`CPA_HORIZON_S`], it brings the two closer than the hull
//! (and closer than they are now) — the velocity-obstacle test of Fiorini and Shiller
//! (*Motion planning in dynamic environments using velocity obstacles*, IJRR 1998). A sonar
//! mover is taken at the largest extent its track has seen, not its last fit, which shrinks
//! when the target crosses against the sweep ([`Tracks::extent`]). A mover
//! can run into a vehicle that stops, so stopping is checked the same way, and when every
//! motion above is blocked and stopping is too, the guard **evades**: the clear heading nearest
//! the commanded one, all round, at the fastest speed it may ask for (the present speed plus
//! one period at F_max, within `speed_cap`: v_max, or less while navigation is late or the
//! sonar loses pings), then half of it. A slow-turning craft stops unless stopping is run
//! into *and* a motion it can make is clear: at 2.6°/s the flat-fish moves sideways 0.4 m in
//! the 7 s two of them take to close from 8 m, while stopping halves the closing speed and
//! leaves the other's guard room to stop too (flat-fish bench with its recipe, seeds 0–67:
//! contacts 8 → 5, successes 552 → 553 of 816; head-on 6 → 3). But a craft that always
//! stopped sat in the way of crossing traffic that does not stop: a mover overtaking it at
//! 0.36 m/s from astern, which at 0.75 m/s it would have outrun, ran into it while it turned
//! on the spot (crossing seed 37). Going on when going on is clear (crossing and head-on,
//! own sonar, recipe, seeds 0–99: contacts 5 → 3, successes 179 → 182 of 200; at 0.75 m/s,
//! seeds 34–133: 15 → 11, 174 → 175; all families, seeds 0–33: 296 → 302 of 408, 0
//! contacts). And when stopping is run into and no motion it can make is clear, it takes the
//! one that keeps farthest from the movers ([`least_bad`], as `evade` does for any craft) if
//! that keeps at least [`GAIN_M`] farther off than stopping: a flat-fish at 1 m/s that stopped
//! for a 0.34 m/s mover crossing from its quarter sat in its way and was run into (perfect
//! perception, crossing seed 22; crossing seeds 0–49 at 1 m/s, contacts 6 → 4, successes
//! 44 → 46; with its sonar and recipe, crossing and head-on seeds 0–99: 182 → 181 of 200,
//! contacts 3 → 2; at 0.75 m/s, seeds 34–133: 175 → 177, 11 → 10). Head-on, stopping and
//! going on keep the same distance, and it stops. Such motions are judged at the present
//! speed plus one period at F_max, so a craft at rest has none: a flat-fish stopped to turn
//! round a rock sat 12 s in the way of a mover it had tracked for 15 s (crossing seed 114).
//! *Tried and not kept:* judging them at its cruise along its course, which gathers way at
//! F_max (with its recipe, seeds 0–33, 34–101 and 102–169: 366 → 363, 714 → 715 and
//! 712 → 715 of 408, 816 and 816; contacts 0 → 0, 1 → 1 and 1 → 0 — the one it was built
//! for); a craft at rest then also went at a mover meeting it head-on, turning 30° off it,
//! to pass a little wider. A clear way out alone at cruise, the least bad as before, left
//! crossing 114 as it was. Nor judging where it stops over the quarter turn it needs to get
//! out of the way (34 s), against the sonar's tracks crossing its course (tried 2026-12-06):
//! a flat-fish that had stopped in a slow mover's way at `--trial 1` (crossing 16) went on
//! instead, but so did one meeting another flat-fish at 90° in a head-on world, which it
//! crossed in front of (head-on 123); crossing and head-on, seeds 0–169 at trials 0 and 1,
//! contacts 12 → 12. Judging such a craft's course over 15 s
//! rather than 10 (from 0.75 m/s it brakes for 7.5 s): at 0.75 m/s, seeds 0–33, contacts
//! 3 → 7, successes 359 → 355 of 408; not kept for the sonar's tracks, whose velocities are
//! a few fits old and wander (over 15 s, with its recipe at `--trial 1`, box fields lost 8 of
//! 170 to phantom movers met too early; contacts 7 → 8). But against a
//! mover whose velocity is measured — a contact the host reports — it is judged over
//! [`SURE_HORIZON_S`] = 15 s: with perfect perception (`hil bench --models flatfish --params
//! hil/recipes/flatfish.toml --sensing contacts --families crossing,head_on,formation
//! --seeds 204`) the flat-fish ran into 34 of 204 crossing movers (up to 1 m/s, against its
//! 0.65): it stopped or turned 10 s before one arrived and coasted into its way (crossing 20:
//! 0.97 m/s from its starboard quarter); over 15 s, 2 (successes 577 → 609 of 612). Not for
//! the other vehicles the host reports: formation mates steer with it, and over 15 s their
//! present velocity put two formations into contact (170 → 167 of 170 at trial 1). With its
//! own sonar nothing changes, run for run. Nor does it meet a sonar track borne out twice at
//! 0.5 m/s or more over 15 s (crossing, head-on and formation at `--trial 1`, seeds 0–169:
//! contacts 6 → 8). Not kept either: a wider berth from movers for such a
//! craft (the hull grown by 1, 2 or 3 m in the closest-approach test; tried 2026-12-05): at
//! 0.75 m/s, crossing and head-on seeds 0–99, contacts 19 → 9, 8, 8 and successes 173 → 186,
//! 186, 187 of 200; but all families, seeds 0–33, 359 → 357 (1 m) and 353 (2 m) of 408, with
//! contacts 3 → 4 and 3 (formations and still worlds lost: the head-on hypothesis's
//! contacts and the mates are held at the berth too), and with the recipe (0.567 m/s, 2 m) 333 → 321, no contact either way.
//! For the sonar's tracked movers alone, not the hypotheses, slow tracks or other vehicles:
//! crossing and head-on, 19 → 14. Nor 0.5 m (2026-12-06, the recipe's 0.65 m/s and its 40 m
//! sonar): crossing, head-on and formation, seeds 0–169, successes 504 → 501 of 510,
//! crossing contacts 1 → 3. Nor going astern (tried 2026-12-06): a craft that stopping
//! leaves in a rated mover's way, with no motion ahead clear, backing straight out at
//! 0.3 m/s when that keeps clear of every mover and runs into nothing still (COLREG rule
//! 8(e), "reversing her means of propulsion"; `v_c` may be negative, the `Command`'s `v_set`
//! would need a new protocol version). It took the flat-fish out of a 0.54 m/s mover's way
//! (crossing 154 at `--trial 1`); but the other flat-fish, rated a mover while it turned on
//! the spot, made it back off in head-on worlds, and the two met later instead (head-on 9 and
//! 24). Crossing, head-on and formation, seeds 0–169 at trials 0 and 1 and seeds 170–305:
//! contacts 7 → 7, successes 1 405 → 1 405 of 1 428; NUCLEO flash +300 B. Anything slower
//! than [`STILL_MPS`] is judged
//! still, not a mover: a stopped vehicle the host reports drifts at a centimetre a second, and
//! weighed as a mover among the others, the least bad way out of a mate closing from astern
//! ran a flat-fish into another mate stopped ahead (formation worlds).
//!
//! **A close call.** A craft that turns slowly and would pass a mover less than
//! [`CLOSE_CALL_M`] clear of its hull — on the command, or on the nearest clear turn — stops
//! instead when stopping keeps it [`GAIN_M`] farther off, both within the horizon and after
//! it ([`Believed::passing`]: stopped, it waits for the mover to pass however long that takes,
//! and one coming at where it stops never does). In flat-fish crossing 72 (`--trial 1`) a
//! mover faster than the craft crossed from its starboard side; the field turned the craft to
//! port, along the mover's course, and the guard kept the nearest clear heading to that. The
//! margin of going on was 0.2–0.7 m and shrank each second, until nothing was clear; stopping
//! 6 s before would have kept 0.9–1.7 m. That run keeps its contact: its mover came at where
//! the craft would have stopped. *Tried first:* the same without the wait for the mover to
//! pass. Two flat-fish meeting head-on then stopped in turn as each came on, stopping only
//! putting the other's arrival beyond the horizon, and they met (head-on 31, at trials 0 and
//! 1). The flat-fish with its recipe, crossing, head-on and formation, seeds 0–169 at trials
//! 0–3 (`cargo hil bench --models flatfish --params hil/recipes/flatfish.toml --families
//! crossing,head_on,formation --seeds 170 --trial K`): contacts 12 → 5 (10 gone, 3 new).
//!
//! **Lag.** A sonar mover is carried from its last sighting on its track's velocity, which
//! the tracker's filter closes on by a third a sweep, so a mover unseen for a while may be
//! farther on than that. A sonar mover whose velocity a sighting has borne out
//! ([`Tracks::borne_out`]) and that stands alone is grown by [`LAG`] (a fifth) of the way its
//! track says it has come since it was last seen: 0.6 m after 3 s at 1 m/s. In held-out
//! crossing 1002 the tracker rated a 0.96 m/s mover at 0.76 m/s. Three seconds after its last
//! sighting it was 0.6–0.7 m farther on than believed, and the VideoRay pacing it turned into
//! it. *Tried first:* growing every sonar mover. The phantom movers of channel walls then
//! closed channels: VPF, seeds 1000–1199, 6 channels lost, and the median guard periods per
//! run rose by a fifth to a half in every family. As kept, VPF, seeds 1000–1199 (`cargo hil
//! bench --first-seed 1000 --seeds 200`): 2 395 → 2 396 of 2 400, contacts 3 → 2, nothing
//! lost; seeds 0–199 with the same outcomes run for run, 2000–2199 but for one channel turned
//! over, no contact either way; median guard periods per run on seeds 0–199: wall gaps
//! 43 → 49, formations 1 045 → 1 016, the others within 3. Multipoint and navfn, seeds
//! 0–199: 4 614 → 4 611 of 4 800 (two multipoint formations and four navfn wall gaps lost,
//! three navfn worlds gained), contacts 1 → 1.
//!
//! **Head-on.** A sonar contact seen once has no velocity yet, and the next look is a sweep
//! (9 s) away. Another vehicle meeting this one head-on closes at twice the cruise speed: seen
//! at 10–15 m, it arrives before the second look, and both vehicles, each believing the other
//! still, steered round where it had been (generated head-on worlds, own sonar: 8 contacts in
//! 400). So a contact seen once within [`HEAD_ON_CONE_RAD`] of the bow that stands alone
//! (nothing else believed within [`HEAD_ON_ALONE_M`] of it: a pier's end or a rock's far
//! face is structure) and is sized as a mover ([`Tracks::mover_sized`]: below) is also
//! judged as a mover at `head_on_mps` (default 1 m/s, a VideoRay's cruise; 0: off), carried
//! from its sighting like any mover: if it stands in open water (nothing within twice that
//! distance), on the course that meets this vehicle's present velocity first (the worst of
//! the courses it may be on, [`intercept`]); otherwise, or if at that speed it cannot meet
//! it, on the reciprocal course. Dead ahead the two are
//! the same; off the bow, the reciprocal course alone let two vehicles that had rounded an
//! obstacle on opposite sides meet at 65°, each seen once 9 m off, neither guard acting.
//! Generated worlds, own sonar, seeds 0–599 × 3 strategies, contacts: head-on 41 → 26,
//! channels 56 → 63 (a wall's first echo ahead is such a contact; with the meeting course
//! for every contact, 29 and 67). A rock seen for the first time ahead costs at most a turn
//! off it until its second look finds it where it was. This is COLREG rule 14's situation (*International Regulations for Preventing
//! Collisions at Sea*, 1972), judged without knowing the other's course; the rule's "both
//! alter to starboard" was tried too (a contact dead ahead must pass to port) and made
//! navfn's head-on contacts 2 → 12 in 400 worlds: each vehicle's planner had already chosen
//! a side. Keeping to starboard of the track before anything is seen (each vehicle steering
//! for a point 4 r₀ = 2 m to the right of its goal, less within 2σ_c of it, so that two on
//! reciprocal tracks pass port to port unseen) was noise: crossing and head-on × 3
//! strategies, seeds 200–399 × trials 0 and 1, contacts 6 → 5 (6 gone, 5 new) — the rocks
//! they round put them back on each other's track.
//!
//! *Sized as a mover* means fitted as a circle, or as a bar that the tracker would let move
//! and that is no longer than the vehicles the planner knows (`agent_radius_m`, the r₀ of
//! 000 §III). Only a circle was asked for; but another flat-fish is fitted as a bar 3.6 m long,
//! and two of them closing head-on at 0.75 m/s never took each other for vehicles, and met
//! (head-on seed 83). To a VideoRay the rule takes another VideoRay fitted as a bar under
//! 0.5 m: 14 of 3 600 crossing and head-on runs (seeds 0–599 × 3) change, contacts 55 → 56.
//! A circle is taken whatever its size; taking only one the tracker sized as a mover (not
//! wider than a vessel, nor a fragment the map's structure runs on through; tried
//! 2026-12-06) changed nothing that counts: VPF, crossing, head-on, channels, wall gaps and
//! serpentines, seeds 0–199, 999 → 998 of 1 000, no contact either way, the same median
//! guard periods.
//!
//! *Measured and left as it is* (crossing and head-on worlds × 3 strategies, seeds 0–599,
//! 55 contacts in 3 600 runs as it was then): the meeting course is looked for within
//! [`CPA_HORIZON_S`] *of the sighting*, so a contact seen 25 m ahead, which would meet this
//! vehicle 13 s later, is held on the reciprocal course for good. Counted from now, it is
//! met on its meeting course once that is 10 s off, and two VideoRays that had seen each
//! other once would have turned; but contacts rose to 96, most of them crossing movers run
//! into while the guard turned from a hypothetical one. The hypothesis also for a track seen
//! twice whose velocity no third sighting has confirmed: 77. Half the cruise speed while a
//! contact of unknown motion is within 20 m ahead (COLREG rule 6, safe speed): 74 — a slower
//! vehicle stays longer in the crossing traffic's way. The same hypothesis for a blob of
//! believed map cells (within 1 m) that stands alone ahead, for another vehicle whose weak
//! echoes reach only the evidence map (VPF head-on seed 248, trial 1: each took the other for
//! cells of a rock 6 m ahead and neither turned; so did head-on 445 of seeds 400–599): a
//! mover on the reciprocal or meeting course, beyond the stopping distance, at most two a
//! period. Crossing and head-on × 3 strategies: seeds 200–399, contacts 2 → 5 at trial 0 and
//! 4 → 3 at trial 1 (the new ones pairs that never believed each other at all); seeds
//! 400–599, 3 → 1 and 8 → 7 — head-on 9 → 1, but crossing 2 → 7, and leaving out a blob on a
//! tracked mover's wake (the way it came over the horizon) changed none of those. Not kept.
//! Without a floor at the stopping distance it also swerved vehicles onto speckle cells about
//! the head, which held them "inside an obstacle" for good (10 of 400 VPF runs), until
//! `crate::sonar::EvidenceMap::nearest` passed over a cell under the vehicle's centre.
//!
//! **Close quarters.** Two VideoRays that meet head-on see each other late: a 0.4 m hull is
//! narrower than the gap between the 3° beams of a 3.6° step, so beyond about 5 m it is one
//! beam of a weak echo, which the extractor cannot tell from a false target, and it becomes a
//! contact only a few metres off. Both guards then stopped (head-on seed 354: 2.2 m apart);
//! but a contact seen once is a point, and the head-on hypothesis carries it past along the
//! reciprocal course. Two seconds later each guard believed the other gone by, each vehicle's
//! field steered it round where the other had been, and they met side by side 1.2 m from
//! there. So such a contact (seen once, sized as a mover, standing alone) near enough to
//! matter is also judged as its shape grown by how far it may have come since, in any
//! direction, at [`CLOSE_DRIFT`] × `head_on_mps` for at most [`CLOSE_DRIFT_S`]: once that
//! reaches the vehicle, the guard lets it move only away. A vehicle that has seen this one
//! comes on slowly — its guard holds it — hence half the speed; and by the time the head has
//! looked again, one that close would have been seen again. The grown contact is its own
//! floor (moving away from it is allowed however deep inside the vehicle is), not the
//! vehicle's clearance to everything: a first draft let that clearance, deep inside a
//! 13 s-old pier fragment's reach, loosen the keep-off from the pier beside it, and a
//! multipoint VideoRay crept into it (harbour seed 128). It is not a mover's circle, which
//! would take a second slot in the guard's table. Not for a craft that turns slowly: it cannot
//! move only away, and another flat-fish is seen on many beams at range (the flat-fish with
//! its recipe, seeds 0–33: 333 → 327 of 408, contacts 0 → 2, mates in formation creeping
//! together). Crossing and head-on × 3 strategies, held-out seeds 200–399, trials 0 and 1
//! (`cargo hil bench --families head_on,crossing --strategies vpf,multipoint,navfn
//! --first-seed 200 --seeds 200 --trial K`): contacts 8 → 6 (head-on 354 and 395 gone, none
//! new), successes 2 391 → 2 393 of 2 400; VPF, all families, seeds 0–199: 2 398 → 2 398,
//! 0 → 0, row for row. The contacts left are vehicles that saw each other within 2 m and
//! turned into each other while stopping (head-on 292), or that neither saw before they
//! touched (head-on 248: converging side by side at 1 m/s, both in transit).
//!
//! *A vessel that was closing* is judged the same way, from where it was last seen: a sonar
//! mover no larger than another VideoRay whose velocity a sighting has borne out
//! ([`Tracks::vessel`]), that was coming towards this vehicle and stands alone. Its own guard
//! may have stopped and turned it since. In held-out head-on 2000 each VideoRay had rated the
//! other; one's guard stopped it 2 m off and it turned onto the other's course, while the
//! other, carrying it on at its last velocity, now behind it, steered into it. The simulated
//! sonar's spurious echoes pair into phantom movers of that size ("Faint pairs" in
//! `crate::guidance::tracks`), which nothing bears out: met too, they raised the median
//! guard periods per run by a sixth in every family. VPF, seeds 2000–2199 (`cargo hil bench
//! --first-seed 2000 --seeds 200`): 2 395 → 2 396 of 2 400, contacts 1 → 0; seeds 0–199 and
//! 1000–1199 run for run the same (median guard periods per run: crossing 24 → 26.5,
//! head-on 37.5 → 40.5); multipoint and navfn, seeds 0–199, 4 613 → 4 612 (a navfn wall gap
//! timed out), contacts 1 → 1. Not for a craft that turns slowly, as above.
//!
//! The guard runs after the planner's step, outside its 100 000-instruction budget. Its worst
//! case for this and the head-on hypothesis, every table slot a contact seen once ahead and
//! alone, is a phase of `cargo selftest` (a VideoRay at cruise among 32 of them, 4.7 m apart):
//! the whole period is at most 512 560 instructions with the evidence map empty (the nearest
//! contact, 3 m ahead, in close quarters) and 727 360 with its 32 cells, which every "alone"
//! test reads; about 4 ms of the 100 ms period at the STM32G431's 170 MHz.
//!
//! **Mates may stop.** A craft that turns slowly also judges the other vehicles the host
//! reports where they are now, as if they stopped, besides on their closest approach: each
//! has a guard of its own. In formation worlds a flat-fish with a mate closing from astern
//! could not stop (it would be run into), so its way out went on towards a mate ahead that
//! was moving off at 0.2 m/s — whose guard then stopped it, and the two met (formations 140
//! and 209 of `hil bench --models flatfish --params hil/recipes/flatfish.toml`). With it,
//! formations of seeds 0–237: 233 → 237 of 238 at trial 0, contacts 2 → 0; 238 → 238 at
//! `--trial 1`, no contact either way. Not for a craft that turns at once, which stops
//! within a metre: for the VideoRay (VPF, multipoint and navfn formations, seeds 0–199)
//! multipoint lost 2 of 200, with no contact either way.
//!
//! **Slow tracks.** A sonar track whose sightings a sweep apart put it on the move at 0.3–0.5
//! m/s stays still in the table until a third sighting lands where that velocity says (a
//! rock's fits wander at such speeds: `crate::guidance::tracks`, "Slow movers"). Two
//! flat-fish closing head-on at about 0.5 m/s each, each believing the other still, each
//! stopped a braking distance short of where it believed the other to be, and met (head-on
//! seed 11). The guard meets such a track on that velocity too ([`Tracks::tentative`]); the
//! planner's field still takes it for still. For a track once a mover coming on that a miss
//! has made still, from 0.2 m/s rather than 0.3 (`crate::guidance::tracks`, "Once a mover").
//! Both changes together, flat-fish, seeds 0–135 (1 632 runs): with its recipe contacts 7 → 5 and successes 1 161 → 1 164; at 0.75 m/s
//! contacts 21 → 13 (head-on 8 → 3). Once the third sighting is overdue — the track unseen
//! for a sweep ([`CPA_HORIZON_S`]) — the velocity was a rock's wander and is not met: a rock
//! fragment seen twice 28 s before, carried 3.4 m along its wander, turned a VideoRay away
//! from a waypoint it had to pass (`hil/scenarios/waypoints_through_clutter.toml`). A
//! VideoRay's guard met none of them before: meeting fresh ones, crossing and head-on ×
//! 3 strategies, held-out seeds 200–399, contacts 23 → 17 (6 gone, none new), seeds 0–199
//! 15 → 14; all families × 3, seeds 0–199, successes 6 977 → 6 971 (p = 0.5), median
//! guard periods per run on the ten static families 26 → 29, 44 → 51, 29 → 34. When it met
//! every tentative track, fresh or not, on seeds 0–199 × 3 its median interventions per run
//! rose by a quarter (rocks' wandering fits) and the shipped waypoint mission above missed a
//! waypoint.
//!
//! A craft that turns slowly also meets on that velocity a track that has drifted far from its
//! first sighting at a slow filter speed, borne out or not, when it stands alone ([`alone`]:
//! nothing else believed within [`HEAD_ON_ALONE_M`], as the head-on hypothesis asks of a
//! vehicle; `crate::guidance::tracks`, "Drifting"). A VideoRay steps out of a slow mover's way
//! once a sighting bears it out; and a rock whose track a mover had handed over is far from
//! that track's first sighting: met as drifting, it turned a VideoRay into the way of a
//! 1 m/s mover behind it (crossing 851 at `--trial 1`).
//!
//! **Unmapped tracks.** While an evidence map is in use, still sonar tracks are left to it
//! ([`World::left_to_map`]): its cells, not the fits, are what the field and the guard meet. A
//! small box (2.2 × 1 m) fitted twice from 12–17 m never made a believed cell — its echoes
//! never reached two in one — and a navfn VideoRay that had turned about 7 m from it ran into
//! it at 1 m/s, the table holding it all the while and the route's detour point on it (bench
//! boxes seed 90). So a still track seen more than once, near enough to block a segment,
//! with none of this period's map cells within its extent (and a cell's half-diagonal) is
//! judged as its shape too, and counts in the clearance the vehicle has now. Where the map
//! shows it, it speaks for it as before; cells hidden behind a nearer one in the same bearing
//! sector make a track judged twice, which errs on the safe side. All families × 3
//! strategies, seeds 0–199: that contact went, and no other run changed; crossing and head-on
//! seeds 200–399: run for run the same.
//!
//! **Lookout.** What was never believed cannot block a motion, and the sonar believes only
//! what it has looked at. So the command also goes no faster than the vehicle can stop from,
//! hull and margin included, within the way the sonar last saw clear in its direction
//! (`crate::sonar::lookout`: of the head's last pass over that bearing, the beam that saw
//! farthest, its end's distance along the track less how far beyond the hull to the side it
//! ran), and never slower than `lookout_mps` (0.25 m/s), at which it goes on until the head
//! comes round. Its direction is the commanded heading, or for a slow-turning craft the
//! heading it has. In transit the head looks ahead once a sweep and this does not bind; it
//! binds when the vehicle turns with the head, or into a bearing last looked along from
//! elsewhere. A VideoRay that had spun round at a channel's bend ran at 1 m/s into the outer
//! wall, whose stretch ahead no beam had looked at for 16 s (channel 136); so did four more of
//! 10 800 runs (seeds 0–299 × 3 strategies). Taking the latest beam of a bearing rather than the
//! farthest of the head's last pass: contacts with movers (crossing and head-on, seeds 0–599 ×
//! 3) 56 → 62 (another vehicle beside the track stops a few beams short). Setting no bound
//! when the beam ended on something believed in the way, or on a mover's recent track (the
//! checks here judge those), changed no mover contact, and let a navfn VideoRay run into a
//! wall whose first echo the head-on hypothesis had made a mover (channel 110). *Left as it
//! is:* the floor is the risk. A VPF VideoRay beside a channel's wall (held-out channel 254),
//! turned about by the guard, crept at 0.25 m/s into the wall 0.6 m off its side, whose
//! stretch there the map did not believe and whose bearings the head had last looked along
//! from 8 m away (`hil beliefs … --at 157` prints the lookout ahead). Withholding the floor
//! when the kept beam ended on an echo in the hull's way changed nothing there.
//!
//! Cost: one point-to-segment distance per map cell and still agent per heading tried, samples
//! every [`SAMPLE_M`] along the segment for the table's still obstacles near enough to matter,
//! and one closest-approach per mover ([`TRACK_STEPS`] of them for a slow-turning craft);
//! once a period, a distance per map cell for each still track seen again within reach
//! (at most 32 × 32); for each contact seen once ahead, two "alone" tests over the table and
//! the map's cells. The worst cases: a slow-turning craft in traffic closing from all round,
//! which searches every heading twice for a clear motion and once more for the least bad
//! (`cargo selftest`'s flat-fish in traffic, whole period at most 437 400 instructions, the
//! planner's step 90 600), and a vehicle among contacts seen once ("Close quarters" above:
//! 727 360).

use super::tracks::Tracks;
use crate::math::{cos, max, min, sin, wrap_angle, Vec2};
use crate::params::Params;
use crate::planner::{Command, Mode, NavState};
use crate::sonar::EvidenceMap;
use crate::world::{Origin, World, MAX_AGENTS, MAX_MAP_CELLS, MAX_OBSTACLES};

// One bit per map cell (`Believed::cells`).
const _: () = assert!(MAX_MAP_CELLS <= 32);

/// Map cell `i`'s bit in `Believed::cells`.
fn bit(i: usize) -> u32 {
    u32::try_from(i)
        .ok()
        .and_then(|i| 1u32.checked_shl(i))
        .unwrap_or(0)
}

/// Spacing of the clearance samples along the segment for table obstacles, m.
pub const SAMPLE_M: f32 = 0.25;
/// How long a motion is held when it is judged against movers, s: about a sonar sweep (9 s for
/// a Micron at 30 m), the longest a mover goes unseen.
pub const CPA_HORIZON_S: f32 = 10.0;
/// How long a slow-turning craft's course is judged against a mover whose velocity is measured
/// (a contact or vehicle the host reports), s: from its cruise it takes 6–7 s to stop, and the
/// mover goes on meanwhile (module notes, "Movers"). Against a sonar track, [`CPA_HORIZON_S`].
pub const SURE_HORIZON_S: f32 = 15.0;
/// Bearings off the bow within which a contact seen once may be a vehicle meeting this one
/// head-on (module notes), rad.
pub const HEAD_ON_CONE_RAD: f32 = crate::math::PI / 3.0;
/// Such a contact is taken for a vehicle only if nothing else believed is within this of its
/// extent, m.
pub const HEAD_ON_ALONE_M: f32 = 2.0;
/// How fast a contact seen once that may be another vehicle is taken to have come since its
/// sighting, in any direction, as a fraction of `head_on_mps` (module notes, "Close
/// quarters"): a vehicle that has seen this one slows, as its guard holds it.
pub const CLOSE_DRIFT: f32 = 0.5;
/// For how long after its sighting such a contact may go on coming, s: about until the head
/// looks again (`TrackConfig::revisit_ms`), when a vehicle that close would be seen (the
/// simulated sonar makes another VideoRay within 3 m a contact on 19 sweeps in 20).
pub const CLOSE_DRIFT_S: f32 = 4.0;
/// Steps of the course a slow-turning craft is predicted on over [`SURE_HORIZON_S`] when it is
/// judged against movers (one a second; a sonar track is met over the first
/// [`CPA_HORIZON_S`] of them).
pub const TRACK_STEPS: usize = 15;
/// How much farther from a mover than stopping keeps a motion must keep a slow-turning craft
/// before it takes that motion when nothing is clear, m (module notes, "Movers").
pub const GAIN_M: f32 = 0.5;
/// A motion a slow-turning craft would take that passes a mover closer than this beyond the
/// hull, m, while stopping keeps [`GAIN_M`] farther off, is a close call: it stops instead
/// (module notes, "A close call").
pub const CLOSE_CALL_M: f32 = 1.0;
/// The step of [`Helm::course`] at [`CPA_HORIZON_S`].
const STOPPED: usize = (CPA_HORIZON_S * TRACK_STEPS as f32 / SURE_HORIZON_S) as usize;
/// How far a sonar mover may be ahead of where its track carries it, per metre its track says
/// it has come since it was last seen (module notes, "Lag").
pub const LAG: f32 = 0.2;
/// Slower than this, m/s, an obstacle or vehicle is judged still: it moves less than 0.5 m
/// over [`CPA_HORIZON_S`], and a way out of the movers must not run into it (module notes,
/// "Movers"). The sonar tracker gives no velocity below 0.3 m/s; contacts from the host carry
/// a stopped vehicle's drift.
pub const STILL_MPS: f32 = 0.05;

/// Whether velocity `v` is too slow to judge as a mover ([`STILL_MPS`]).
fn still(v: Vec2) -> bool {
    v.norm2() < STILL_MPS * STILL_MPS
}

/// Chords of the arc a slow-turning craft sweeps (module notes): enough to follow a turn of up
/// to a few tenths of a radian within a braking distance.
pub const ARC_SEGMENTS: usize = 4;

/// The guard's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GuardConfig {
    /// Off: commands go out as planned (for reproducing the papers' runs as published).
    pub enabled: bool,
    /// Extra distance beyond the braking distance, m, 0 ..= 10.
    pub margin_m: f32,
    /// Clearance kept beyond the hull radius, m: the vehicle's sway in a turn and the sonar's
    /// range error are not in the check. Not for a craft that turns slowly
    /// ([`GuardConfig::hull_margin`]).
    pub hull_margin_m: f32,
    /// Step between the headings tried, rad.
    pub turn_step_rad: f32,
    /// Largest turn away from the commanded heading, rad.
    pub max_turn_rad: f32,
    /// Slowest speed tried before stopping, m/s.
    pub min_speed: f32,
    /// Speed of the head-on hypothesis, m/s (0: off): a sonar contact seen once, within
    /// [`HEAD_ON_CONE_RAD`] of the bow, is also judged as a mover at this speed on the course
    /// that meets this vehicle, or the reciprocal one (module notes).
    pub head_on_mps: f32,
    /// Slowest speed the lookout holds a vehicle to, m/s (0: no lookout): the speed at which
    /// it goes where its sonar has not looked lately (module notes, "Lookout").
    pub lookout_mps: f32,
}

impl Default for GuardConfig {
    fn default() -> Self {
        GuardConfig {
            enabled: true,
            margin_m: 0.3,
            hull_margin_m: 0.25,
            turn_step_rad: crate::math::PI / 12.0,
            max_turn_rad: crate::math::PI / 2.0,
            min_speed: 0.1,
            head_on_mps: 1.0,
            lookout_mps: 0.25,
        }
    }
}

impl GuardConfig {
    /// The clearance kept beyond the planner's hull radius for the craft `prm` describes:
    /// `hull_margin_m`, or none for a craft that turns slowly (`Params::turn_rate_rps` > 0).
    /// Its check follows the arc the craft sweeps, turn and all, and such a craft's hull is
    /// large next to the margin's reasons: with it, the flat-fish's guard kept 2.85 m off
    /// everything believed, and held it in 8 m channels and between rocks its route led it
    /// through. Flat-fish with its recipe (hull 2.6 m; 2.25 m in the simulator), `cargo hil
    /// bench --models flatfish --params hil/recipes/flatfish.toml --first-seed F --seeds 34`:
    /// seeds 0–33 323 → 332 of 408, 0 → 0 contacts, worst clearance 0.55 → 0.29 m; seeds
    /// 34–67 (held out) 315 → 323, 2 → 2 contacts (crossing movers, −0.01 m); seeds 68–101
    /// outside formations 289 → 286, 0 → 0 (worst clearance 0.50 → 0.20 m): a gain, noisy.
    pub fn hull_margin(&self, prm: &Params) -> f32 {
        if prm.turns_slowly() {
            0.0
        } else {
            self.hull_margin_m
        }
    }
}

/// What the guard did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// The command was clear.
    Clear,
    /// Turned to a clear heading.
    Turned,
    /// Slowed to a clear speed.
    Slowed,
    /// Stopped.
    Stopped,
}

/// Something believed to move, carried to now.
#[derive(Clone, Copy)]
struct Mover {
    /// Centre now, m.
    center: Vec2,
    /// Velocity, m/s.
    velocity: Vec2,
    /// Radius of a circle that covers it, m.
    radius: f32,
}

/// Everything believed, seen from one position.
struct Believed<'a> {
    world: &'a World,
    /// The obstacles and vehicles with a velocity, at their positions now.
    movers: heapless::Vec<Mover, { MAX_OBSTACLES + MAX_AGENTS }>,
    /// The first `sure` of them have a measured velocity — contacts the host reports — not
    /// one inferred from the sonar's fits ([`SURE_HORIZON_S`]; a count, not a flag per mover:
    /// 160 bytes less stack).
    sure: usize,
    /// The map cells that a segment of the longest length tried can reach: bit i for
    /// `world.map_cells()[i]` (a mask, not a copy: the guard's frame is the deepest of the
    /// periodic task's, `cargo selftest`'s stack high-water).
    cells: u32,
    /// The still sonar tracks the map does not show (module notes, "Unmapped tracks"): bit i
    /// for `world.obstacles()[i]`, judged as shapes like charted obstacles.
    unmapped: u32,
    hull: f32,
    /// Radius of another vehicle's circle, m.
    agent_r: f32,
    /// Radius of the disc that covers a map cell, m: a surface anywhere in a believed cell is
    /// within it, so the check errs on the safe side of the grid's resolution.
    r_map: f32,
    /// The contacts seen once that may be vehicles close by, and the vessels that were closing
    /// (module notes, "Close quarters"): bit i for `world.obstacles()[i]`, judged as their
    /// shape grown by how far they may have come since ([`Believed::drift`]).
    close: u32,
    /// Now, ms, and the speed the `close` contacts may have come at since their sighting, m/s.
    now_ms: u64,
    drift_mps: f32,
    /// Whether other vehicles are judged where they are whatever their velocity (a craft that
    /// turns slowly: module notes, "Mates may stop").
    mates_stop: bool,
    /// Clearance at the vehicle's position to what the still check judges (map cells, still
    /// obstacles, and the agents `mates_stop` says), m: the floor of
    /// [`Believed::blocked_still`]. Movers are not in it — they are met on their closest
    /// approach, each with its own floor — and once were: a wall's fragment the tracker had
    /// rated as a mover, sitting in the table 1.4 m from the flat-fish where it was seen 20 s
    /// before, let the still check take the vehicle to 1.4 m of a U-trap's arm, well inside
    /// its hull (generated U-trap 48).
    here: f32,
}

/// The velocity of speed `s` on which something at the origin meets a point that starts at
/// `d` and moves at `v`, the first time it can (within [`CPA_HORIZON_S`]); `None` if it
/// cannot catch it.
fn intercept(d: Vec2, v: Vec2, s: f32) -> Option<Vec2> {
    // |d + v·t| = s·t: (|v|² − s²)·t² + 2·(d·v)·t + |d|² = 0, the smallest t > 0.
    let (a, b, c) = (v.norm2() - s * s, 2.0 * d.dot(v), d.norm2());
    let t = if a.abs() < 1e-6 {
        (b < 0.0).then(|| -c / b)?
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        let q = crate::math::sqrt(disc);
        let (t1, t2) = ((-b - q) / (2.0 * a), (-b + q) / (2.0 * a));
        let (lo, hi) = (min(t1, t2), max(t1, t2));
        if lo > 0.0 {
            lo
        } else if hi > 0.0 {
            hi
        } else {
            return None;
        }
    };
    (t.is_finite() && t > 1e-3 && t <= CPA_HORIZON_S).then(|| (d + v * t) * (1.0 / t))
}

/// Distance from `c` to the segment from `a` along unit `u` for `len` m.
fn to_segment(c: Vec2, a: Vec2, u: Vec2, len: f32) -> f32 {
    let t = max(0.0, min((c - a).dot(u), len));
    (c - (a + u * t)).norm()
}

impl Believed<'_> {
    /// Whether moving from `p` along unit `u` for `len` m at `speed` m/s goes below the hull
    /// radius and below the clearance we have now, against what stands still; and whether
    /// holding that velocity meets a mover (see [`Believed::meets_mover`]).
    fn blocked(&self, p: Vec2, u: Vec2, len: f32, speed: f32) -> bool {
        self.blocked_still(p, u, len) || self.meets_mover(p, u * speed)
    }

    /// The still part of [`Believed::blocked`].
    fn blocked_still(&self, p: Vec2, u: Vec2, len: f32) -> bool {
        let floor = min(self.hull, self.here - 1e-3);
        let w = self.world;
        // Points: map cells (discs covering the whole square cell) and still agents (circles of
        // the vehicle's own radius, 000 §III, so hull + hull).
        let r_map = self.r_map;
        if w.map_cells()
            .iter()
            .enumerate()
            .filter(|&(i, _)| self.cells & bit(i) != 0)
            .any(|(_, &c)| to_segment(c, p, u, len) - r_map < floor && ahead(c, p, u))
        {
            return true;
        }
        let judged = |a: &&crate::world::Agent| self.mates_stop || still(a.velocity);
        if w.agents().iter().filter(judged).any(|a| {
            to_segment(a.position, p, u, len) - self.agent_r < floor && ahead(a.position, p, u)
        }) {
            return true;
        }
        // Shapes: sampled along the segment, only those that can reach it.
        let samples = (len / SAMPLE_M) as u32 + 1;
        let judged = |(i, o): &(usize, &crate::world::Obstacle)| {
            let close = self.close & bit(*i) != 0;
            close || still(o.velocity) && (!w.left_to_map(o) || self.unmapped & bit(*i) != 0)
        };
        for (i, o) in w.obstacles().iter().enumerate().filter(judged) {
            let grown = self.drift(i, o);
            let reach = (o.shape.center() - p).norm() - o.shape.bounding_radius() - grown;
            if reach > len + self.hull {
                continue;
            }
            // A close contact's reach is its own floor: inside it the vehicle may move away
            // from it, and what it believes stands still is judged as before.
            let floor = if grown > 0.0 {
                min(self.hull, o.shape.signed_distance(p) - grown - 1e-3)
            } else {
                floor
            };
            if (1..=samples).any(|k| {
                let s = min(k as f32 * SAMPLE_M, len);
                o.shape.signed_distance(p + u * s) - grown < floor
            }) {
                return true;
            }
        }
        false
    }

    /// How far obstacle `o` (index `i`) may have come since its sighting, m: 0 unless it is a
    /// close contact (module notes, "Close quarters").
    fn drift(&self, i: usize, o: &crate::world::Obstacle) -> f32 {
        if self.close & bit(i) == 0 {
            return 0.0;
        }
        drifted(
            self.drift_mps,
            self.now_ms.saturating_sub(o.seen_ms) as f32 * 1e-3,
        )
    }

    /// [`Believed::blocked_still`] along a polyline: each chord is a segment of its own.
    fn blocked_path(&self, pts: &[Vec2]) -> bool {
        pts.windows(2).any(|w| match w {
            [a, b] => (*b - *a)
                .normalized(1e-4)
                .is_some_and(|u| self.blocked_still(*a, u, (*b - *a).norm())),
            _ => false,
        })
    }

    /// Whether holding velocity `v` from `p` for [`CPA_HORIZON_S`] brings a mover within the
    /// hull, and nearer than it is now (so moving away from one already close is allowed).
    fn meets_mover(&self, p: Vec2, v: Vec2) -> bool {
        self.mover_margin(p, v) < 0.0
    }

    /// How far, at the worst, holding `v` keeps clear of that limit over the movers, m
    /// (`INFINITY` with none).
    fn mover_margin(&self, p: Vec2, v: Vec2) -> f32 {
        self.movers.iter().fold(f32::INFINITY, |worst, m| {
            let closest = closest_approach(m.center - p, m.velocity - v, CPA_HORIZON_S);
            min(worst, self.clear_of(m, p, closest - m.radius))
        })
    }

    /// How far, at the worst, the movers pass clear of a vehicle stopped at `at` from `after_s`
    /// s on, however long they take to pass (no horizon: one coming straight at it does not
    /// pass), m.
    fn passing(&self, at: Vec2, after_s: f32) -> f32 {
        self.movers.iter().fold(f32::INFINITY, |worst, m| {
            let d = m.center + m.velocity * after_s - at;
            let closest = closest_approach(d, m.velocity, f32::INFINITY);
            min(worst, self.clear_of(m, at, closest - m.radius))
        })
    }

    /// How far a closest approach of `closest` m to mover `m` keeps clear of the limit: the
    /// hull, or the clearance the vehicle at `p` has now if that is less (moving away from a
    /// mover already close is allowed), m.
    fn clear_of(&self, m: &Mover, p: Vec2, closest: f32) -> f32 {
        let now = (m.center - p).norm() - m.radius;
        closest - min(self.hull, now - 1e-3)
    }

    /// [`Believed::mover_margin`] for a craft that follows `track` (positions at
    /// [`TRACK_STEPS`] equal steps over [`SURE_HORIZON_S`]) rather than holding one velocity:
    /// within each step both it and the mover move straight, so the closest approach of that
    /// step is the distance from the origin to the segment their offsets trace. A sonar
    /// track is met over the first [`CPA_HORIZON_S`] only.
    fn mover_margin_along(&self, track: &[Vec2; TRACK_STEPS + 1]) -> f32 {
        let dt = SURE_HORIZON_S / TRACK_STEPS as f32;
        let p = track[0];
        self.movers
            .iter()
            .enumerate()
            .fold(f32::INFINITY, |worst, (i, m)| {
                let at = |k: usize, x: Vec2| m.center + m.velocity * (k as f32 * dt) - x;
                let horizon = if i < self.sure {
                    SURE_HORIZON_S
                } else {
                    CPA_HORIZON_S
                };
                let closest = track
                    .windows(2)
                    .take((horizon / dt) as usize)
                    .enumerate()
                    .fold(f32::INFINITY, |c, (k, w)| match w {
                        [a, b] => {
                            let (d0, d1) = (at(k, *a), at(k + 1, *b));
                            let len = (d1 - d0).norm();
                            let d = match (d1 - d0).normalized(1e-6) {
                                Some(u) => to_segment(Vec2::ZERO, d0, u, len),
                                None => d0.norm(),
                            };
                            min(c, d)
                        }
                        _ => c,
                    })
                    - m.radius;
                min(worst, self.clear_of(m, p, closest))
            })
    }
}

/// The closest two points come within `horizon_s` from now, at offset `d` and relative velocity
/// `w`, m. Inlined: it runs per mover per heading tried, and as a call it cost the guard's
/// worst case (`cargo selftest`, contacts seen once) 19 500 instructions more.
#[inline(always)]
fn closest_approach(d: Vec2, w: Vec2, horizon_s: f32) -> f32 {
    let w2 = w.norm2();
    let t = if w2 > 1e-9 {
        max(0.0, min(-d.dot(w) / w2, horizon_s))
    } else {
        0.0
    };
    (d + w * t).norm()
}

/// Whether obstacle `o` (of extent `extent`, m) stands alone: nothing else believed within
/// `room` m of it. A fragment of structure (a pier's end, a rock's far face, a wall's run)
/// lies against other believed obstacles or cells; a vehicle or a drifting object in open
/// water stands alone. `r_map`: the evidence map's cell half-diagonal, m.
pub(crate) fn alone(
    world: &World,
    o: &crate::world::Obstacle,
    extent: f32,
    room: f32,
    r_map: f32,
) -> bool {
    let c = o.shape.center();
    let apart = extent + room;
    world
        .obstacles()
        .iter()
        .filter(|q| q.id != o.id)
        // The bounding circle first: no nearer than the shape, and cheaper.
        .all(|q| {
            (q.shape.center() - c).norm() - q.shape.bounding_radius() > apart
                || q.shape.signed_distance(c) > apart
        })
        // Its own echoes are believed cells within a cell of its extent.
        && world.map_cells().iter().all(|&m| {
            let d = (m - c).norm() - extent;
            d <= 2.0 * r_map || d > room + r_map
        })
}

/// How far a close contact seen `age_s` s ago may have come at `mps` m/s, m (module notes,
/// "Close quarters").
fn drifted(mps: f32, age_s: f32) -> f32 {
    mps * min(age_s, CLOSE_DRIFT_S)
}

/// Whether `c` is not behind the vehicle (a disc behind cannot be entered by moving forward,
/// though the segment's start is its nearest point).
fn ahead(c: Vec2, p: Vec2, u: Vec2) -> bool {
    (c - p).dot(u) > 0.0
}

/// Braking distance from `v` at [`Params::brake`], plus what one period covers and the
/// margin, m.
fn reach(v: f32, prm: &Params, cfg: &GuardConfig) -> f32 {
    v * prm.period_s + v * v / (2.0 * prm.brake()) + cfg.margin_m
}

/// The polyline a slow-turning craft sweeps (module notes): from `p` on heading `heading`,
/// turning towards `psi` at most at `turn_rate`, at `speed` for `hold_s`, then braking at
/// `brake` to a stop, then `margin` straight on; [`ARC_SEGMENTS`] chords and the margin.
/// Its skid `sway` (m/s, to port of the heading) is carried at its present rate the whole way
/// ("Skid" in the module notes).
#[allow(clippy::too_many_arguments)]
fn arc(
    p: Vec2,
    heading: f32,
    psi: f32,
    (speed, sway): (f32, f32),
    hold_s: f32,
    brake: f32,
    turn_rate: f32,
    margin: f32,
) -> [Vec2; ARC_SEGMENTS + 2] {
    let turn = wrap_angle(psi - heading);
    let total = hold_s + speed / brake;
    let dt = total / ARC_SEGMENTS as f32;
    let heading_at = |t: f32| heading + max(-turn_rate * t, min(turn, turn_rate * t));
    let mut pts = [p; ARC_SEGMENTS + 2];
    let mut at = p;
    for (k, pt) in pts.iter_mut().enumerate().skip(1).take(ARC_SEGMENTS) {
        let t = (k as f32 - 0.5) * dt;
        let v = if t <= hold_s {
            speed
        } else {
            max(0.0, speed - brake * (t - hold_s))
        };
        let u = Vec2::from_angle(heading_at(t));
        at += (u * v + u.perp() * sway) * dt;
        *pt = at;
    }
    if let Some(last) = pts.last_mut() {
        *last = at + Vec2::from_angle(heading_at(total)) * margin;
    }
    pts
}

/// How the vehicle would move under a command: the straight segment of a craft that turns at
/// once, or the arc of one that turns slowly (module notes).
struct Helm<'a> {
    cfg: &'a GuardConfig,
    prm: &'a Params,
    p: Vec2,
    /// Heading now, rad.
    heading: f32,
    /// Speed over ground now, m/s.
    speed: f32,
    /// Sideways speed now, m/s, positive to port: the skid of a slow-turning craft.
    sway: f32,
}

impl Helm<'_> {
    /// The arc swept by the command (`psi`, `v`), reaction time included.
    fn commanded(&self, psi: f32, v: f32) -> [Vec2; ARC_SEGMENTS + 2] {
        let (prm, cfg) = (self.prm, self.cfg);
        let s = max(v, self.speed);
        let brake = prm.brake();
        let rate = prm.turn_rate_rps;
        arc(
            self.p,
            self.heading,
            psi,
            (s, self.sway),
            prm.period_s,
            brake,
            rate,
            cfg.margin_m,
        )
    }

    /// Where a slow-turning craft is over [`SURE_HORIZON_S`] under the command (`psi`, `v`):
    /// its heading turns towards `psi` at its rate, its speed goes from the present one
    /// towards `v` at F_max or its braking; [`TRACK_STEPS`] + 1 positions, now first.
    fn course(&self, psi: f32, v: f32) -> [Vec2; TRACK_STEPS + 1] {
        let prm = self.prm;
        let turn = wrap_angle(psi - self.heading);
        let rate = prm.turn_rate_rps;
        let dt = SURE_HORIZON_S / TRACK_STEPS as f32;
        let change = v - self.speed;
        let mut pts = [self.p; TRACK_STEPS + 1];
        let mut at = self.p;
        for (k, pt) in pts.iter_mut().enumerate().skip(1) {
            let t = (k as f32 - 0.5) * dt;
            let heading = self.heading + max(-rate * t, min(turn, rate * t));
            let speed = self.speed + max(-prm.brake() * t, min(change, prm.f_max * t));
            at += Vec2::from_angle(heading) * (max(0.0, speed) * dt);
            *pt = at;
        }
        pts
    }

    /// How far, at the worst, the command (`psi`, `v`) keeps clear of the movers, m
    /// ([`Believed::mover_margin`]): held as a velocity by a craft that turns at once, along
    /// its [`Helm::course`] by one that turns slowly (it goes where it points, not where it
    /// is told, and cannot stop at once either).
    fn mover_margin(&self, b: &Believed, psi: f32, v: f32) -> f32 {
        if !self.prm.turns_slowly() {
            return b.mover_margin(self.p, Vec2::from_angle(psi) * v);
        }
        b.mover_margin_along(&self.course(psi, v))
    }

    /// Whether the command (`psi`, `v`) is blocked ([`Believed::blocked`]).
    fn blocked(&self, b: &Believed, psi: f32, v: f32) -> bool {
        self.blocked_still(b, psi, v) || self.mover_margin(b, psi, v) < 0.0
    }

    /// Whether the command (`psi`, `v`) is blocked by what stands still.
    fn blocked_still(&self, b: &Believed, psi: f32, v: f32) -> bool {
        if !self.prm.turns_slowly() {
            return b.blocked_still(self.p, Vec2::from_angle(psi), reach(v, self.prm, self.cfg));
        }
        b.blocked_path(&self.commanded(psi, v))
    }
}

fn with_motion(mut cmd: Command, heading: f32, speed: f32, verdict: Verdict) -> Command {
    let psi = wrap_angle(heading);
    cmd.psi_set = psi;
    cmd.v_set = speed;
    cmd.velocity = Vec2::new(cos(psi), sin(psi)) * speed;
    cmd.setpoints.phi_c = psi;
    cmd.setpoints.v_c = speed;
    cmd.setpoints.a_c = 0.0;
    cmd.setpoints.alpha_c = 0.0;
    cmd.setpoints.omega_c = 0.0;
    if verdict != Verdict::Clear {
        // Not the plan: no integral push (the planner restarts it, `restart_integral`).
        cmd.setpoints.i_surge = 0.0;
        cmd.mode = Mode::Guarded;
    }
    cmd
}

/// The fastest the vehicle at `p` may go along `going` by what `map`'s lookout vouches for
/// (module notes, "Lookout"): the speed from which it stops, hull and margin included, within
/// the clear way the sonar last saw that way, but not under `cfg.lookout_mps`. No bound
/// (infinity) for a vehicle whose sonar never spoke: it perceives by contacts.
fn lookout(
    cfg: &GuardConfig,
    prm: &Params,
    hull: f32,
    map: &EvidenceMap,
    p: Vec2,
    going: f32,
) -> f32 {
    if cfg.lookout_mps <= 0.0 || !map.lookout().any() {
        return f32::INFINITY;
    }
    let clear = map.clear_ahead(p, going, hull);
    // v·T + v²/2b + margin + hull = clear, solved for v.
    let (t, a) = (prm.period_s, prm.brake());
    let room = clear.map_or(0.0, |c| c - cfg.margin_m - hull);
    let v = if room > 0.0 {
        a * (crate::math::sqrt(t * t + 2.0 * room / a) - t)
    } else {
        0.0
    };
    max(v, cfg.lookout_mps)
}

/// Checks `cmd` for the vehicle at `nav` at time `now_ms` against `world`, sonar movers at
/// the largest extent their `tracks` have seen, and where the sonar has looked (`map`'s
/// lookout; see the module notes), and returns the command to send with the verdict; an
/// evasion asks for no more than `speed_cap` m/s. Holds pass through unchanged.
#[allow(clippy::too_many_arguments)] // the period's inputs, each borrowed as the caller has it
pub fn check(
    cfg: &GuardConfig,
    prm: &Params,
    now_ms: u64,
    nav: &NavState,
    world: &World,
    tracks: &Tracks,
    map: Option<&EvidenceMap>,
    cmd: Command,
    speed_cap: f32,
) -> (Command, Verdict) {
    if !cfg.enabled || matches!(cmd.mode, Mode::Hold(_)) {
        return (cmd, Verdict::Clear);
    }
    let p = nav.position;
    let speed = nav.velocity.norm();
    // No segment tried is longer than this: cells farther than it (and the hull and a cell)
    // cannot block any, so they are left out once here rather than per heading.
    let longest = max(
        max(reach(cmd.v_set, prm, cfg), reach(speed, prm, cfg)),
        reach(prm.v_max, prm, cfg),
    );
    let r_map = world.map_radius() * core::f32::consts::SQRT_2;
    let near = longest + prm.agent_radius_m + r_map;
    let cells = world
        .map_cells()
        .iter()
        .enumerate()
        .filter(|&(_, c)| (*c - p).norm2() <= near * near)
        .fold(0, |m, (i, _)| m | bit(i));
    // Still tracks seen more than once, near enough to matter, with none of this period's map
    // cells within their extent (module notes, "Unmapped tracks").
    let unmapped = (world.obstacles().iter().enumerate())
        .filter(|(_, o)| world.left_to_map(o) && tracks.seen_again(o.id))
        .filter(|(_, o)| (o.shape.center() - p).norm() - o.shape.bounding_radius() <= near)
        .filter(|(_, o)| {
            let (c, r) = (o.shape.center(), o.shape.bounding_radius() + r_map);
            world.map_cells().iter().all(|&m| (m - c).norm2() > r * r)
        })
        .fold(0, |k, (i, _)| k | bit(i));
    let age = |seen_ms: u64| min(now_ms.saturating_sub(seen_ms) as f32 * 1e-3, CPA_HORIZON_S);
    // A sonar track's last fit may be a sliver of it: take its largest sighting.
    let extent = |o: &crate::world::Obstacle| {
        let r = o.shape.bounding_radius();
        match o.origin {
            Origin::Sonar => tracks.extent(o.id).map_or(r, |e| max(r, e)),
            _ => r,
        }
    };
    let mut movers = heapless::Vec::new();
    // The host's contacts first (their velocity is measured: `Believed::sure`), then the
    // sonar's tracks.
    let moving = |sure: bool| {
        (world.obstacles().iter())
            .filter(move |o| !still(o.velocity) && (o.origin != Origin::Sonar) == sure)
    };
    for o in moving(true).chain(moving(false)) {
        // Unseen for a while, a mover may be farther on than its track says (module notes).
        let lag = if o.origin == Origin::Sonar
            && tracks.borne_out(o.id)
            && alone(world, o, extent(o), HEAD_ON_ALONE_M, r_map)
        {
            LAG * o.velocity.norm() * age(o.seen_ms)
        } else {
            0.0
        };
        // Room for every obstacle and agent: never full.
        let _ = movers.push(Mover {
            center: o.shape.center() + o.velocity * age(o.seen_ms),
            velocity: o.velocity,
            radius: extent(o) + lag,
        });
    }
    let sure = moving(true).count();
    // Head-on: a contact seen once ahead may be another vehicle coming this way, which the
    // sonar sees again only a sweep later, too late at twice the cruise speed: it is met on
    // the course that meets ours, or on the reciprocal one if none does.
    let bow = Vec2::from_angle(nav.heading);
    let reciprocal = bow * -cfg.head_on_mps;
    let head_on = cfg.head_on_mps > 0.0;
    // Close quarters: such a contact near enough to matter may have come any way since (not
    // for a craft that turns slowly: module notes).
    let drift_mps = if prm.turns_slowly() {
        0.0
    } else {
        CLOSE_DRIFT * cfg.head_on_mps
    };
    let mut close = 0u32;
    for (i, o) in (world.obstacles().iter().enumerate())
        .filter(|(_, o)| head_on && o.velocity == Vec2::ZERO && o.origin == Origin::Sonar)
    {
        let c = o.shape.center();
        let ahead = (c - p)
            .normalized(1e-3)
            .is_some_and(|u| u.dot(bow) >= cos(HEAD_ON_CONE_RAD));
        let extent = extent(o);
        let alone = |room: f32| alone(world, o, extent, room, r_map);
        // A vehicle's echo is fitted as a circle, or as a bar no longer than the vehicles the
        // planner knows (another flat-fish as one 3.6 m long); a wall's run as a longer bar.
        let compact = || match o.shape {
            crate::field::Shape::Circle { .. } => true,
            _ => tracks.mover_sized(o.id) && o.shape.bounding_radius() <= prm.agent_radius_m,
        };
        // Farther than it may have come since it was seen and both can close within the
        // horizon, it cannot meet the hull: left out, to save the checks below.
        let reach = (2.0 * cfg.head_on_mps + prm.v_max) * CPA_HORIZON_S;
        let within = (c - p).norm() <= reach + extent + prm.agent_radius_m + cfg.hull_margin(prm);
        let a = age(o.seen_ms);
        let is_close = drift_mps > 0.0 && (c - p).norm() - extent - drifted(drift_mps, a) <= near;
        let meets = ahead && within;
        if !((meets || is_close) && compact() && tracks.unrated(o.id) && alone(HEAD_ON_ALONE_M)) {
            continue;
        }
        if is_close {
            close |= bit(i);
        }
        if meets {
            // In open water it may be on any course; near structure, it comes along it.
            let velocity = alone(2.0 * HEAD_ON_ALONE_M)
                .then(|| intercept(p - nav.velocity * a - c, nav.velocity, cfg.head_on_mps))
                .flatten()
                .unwrap_or(reciprocal);
            let _ = movers.push(Mover {
                center: c + velocity * a,
                velocity,
                radius: extent,
            });
        }
    }
    // A vessel that was closing may have turned or stopped since its last sighting, its own
    // guard acting (module notes, "Close quarters").
    for (i, o) in (world.obstacles().iter().enumerate())
        .filter(|(_, o)| drift_mps > 0.0 && o.origin == Origin::Sonar && !still(o.velocity))
    {
        let d = o.shape.center() - p;
        let closing = o.velocity.dot(d) < 0.0;
        let reach = d.norm() - extent(o) - drifted(drift_mps, age(o.seen_ms));
        let vessel = || tracks.vessel(o.id) && alone(world, o, extent(o), HEAD_ON_ALONE_M, r_map);
        if closing && reach <= near && vessel() {
            close |= bit(i);
        }
    }
    // Slow tracks: the guard meets a sonar track on the velocity its sightings suggest before
    // a third bears it out (the planner still takes it for still) — until that third is
    // overdue: unseen for a sweep, it was a rock's wander. Rated tracks only, never the
    // head-on hypothesis's: room for every obstacle, never full.
    let overdue_ms = (CPA_HORIZON_S * 1000.0) as u64;
    let slow_turning = prm.turns_slowly();
    let slow_tracks = world
        .obstacles()
        .iter()
        .filter(|o| o.velocity == Vec2::ZERO && now_ms.saturating_sub(o.seen_ms) <= overdue_ms);
    for o in slow_tracks {
        let drifts = || slow_turning && alone(world, o, extent(o), HEAD_ON_ALONE_M, r_map);
        if let Some(v) = tracks.tentative(o.id, drifts) {
            let _ = movers.push(Mover {
                center: o.shape.center() + v * age(o.seen_ms),
                velocity: v,
                radius: extent(o),
            });
        }
    }
    for a in world.agents().iter().filter(|a| !still(a.velocity)) {
        let _ = movers.push(Mover {
            center: a.position + a.velocity * age(a.seen_ms),
            velocity: a.velocity,
            radius: prm.agent_radius_m,
        });
    }
    let b = Believed {
        world,
        movers,
        sure,
        cells,
        unmapped,
        close,
        now_ms,
        drift_mps,
        mates_stop: slow_turning,
        hull: prm.agent_radius_m + cfg.hull_margin(prm),
        agent_r: prm.agent_radius_m,
        r_map,
        // Only what the still checks judge: a mover's shape in the table is where it was
        // seen, not where it is (`Believed::here`).
        here: (world.obstacles().iter().enumerate())
            .filter(|(i, o)| {
                still(o.velocity) && (!world.left_to_map(o) || unmapped & bit(*i) != 0)
            })
            .map(|(_, o)| o.shape.signed_distance(p))
            .chain(
                (world
                    .agents()
                    .iter()
                    .filter(|a| slow_turning || still(a.velocity)))
                .map(|a| (a.position - p).norm() - prm.agent_radius_m),
            )
            .fold(
                crate::world::nearest_cell(world.map_cells(), p)
                    .map_or(f32::INFINITY, |(_, d)| d - r_map),
                crate::math::min_num,
            ),
    };
    let helm = Helm {
        cfg,
        prm,
        p,
        heading: nav.heading,
        speed,
        sway: Vec2::from_angle(nav.heading).cross(nav.velocity),
    };
    let evasion = min(speed_cap, min(prm.v_max, speed + prm.f_max * prm.period_s));
    // A mover may run into a vehicle that stops: then stopping is no way out — unless, for a
    // craft that turns slowly, no motion it can make is clear either (module notes, movers).
    // The slow craft's way out is looked for once, here, and only when it is needed.
    let stop_margin = helm.mover_margin(&b, cmd.psi_set, 0.0);
    let run_into = stop_margin < 0.0;
    let slow_escape = (run_into && helm.prm.turns_slowly())
        .then(|| way_out(cfg, &helm, &b, cmd.psi_set, evasion, stop_margin + GAIN_M))
        .flatten();
    let can_stop = !run_into || (helm.prm.turns_slowly() && slow_escape.is_none());
    let get_away = |cmd: Command| match slow_escape {
        Some((a, v)) => (with_motion(cmd, a, v, Verdict::Turned), Verdict::Turned),
        None => evade(cfg, &helm, &b, cmd, evasion),
    };
    // 1. Where the vehicle is going now, within its braking distance (a slow-turning craft
    //    turning towards the commanded heading as it brakes).
    //    A slow-turning craft creeping slower than `STILL_MPS` is at rest here: its drag
    //    takes the last centimetres per second off over tens of seconds, and it waited them
    //    out on a heading its braking path found blocked instead of turning (step 5): boxes
    //    seed 102, 19 s pointing at a box 3 m ahead. Flat-fish with its recipe, seeds 0–33,
    //    358 → 366 of 408; 34–101 (not looked at), 705 → 714 of 816, contacts 2 → 1;
    //    102–169, 694 → 712, 2 → 1.
    let creeping = helm.prm.turns_slowly() && still(nav.velocity);
    if let Some(u) = nav.velocity.normalized(1e-3).filter(|_| !creeping) {
        let braking = speed * speed / (2.0 * prm.brake()) + cfg.margin_m;
        let blocked = if helm.prm.turns_slowly() {
            let path = arc(
                p,
                nav.heading,
                cmd.psi_set,
                (speed, helm.sway),
                0.0,
                prm.brake(),
                prm.turn_rate_rps,
                cfg.margin_m,
            );
            b.blocked_path(&path)
        } else {
            b.blocked_still(p, u, braking)
        };
        if can_stop && blocked {
            return stopped(cmd);
        }
    }
    let planned = cmd.v_set;
    if planned.is_nan() || planned <= 0.0 {
        if can_stop {
            return (cmd, Verdict::Clear);
        }
        return get_away(cmd);
    }
    // 2. The command as planned, no faster than the lookout vouches for where it goes.
    let going = if helm.prm.turns_slowly() {
        nav.heading
    } else {
        cmd.psi_set
    };
    let v = map.map_or(planned, |m| {
        min(planned, lookout(cfg, prm, b.hull, m, p, going))
    });
    // 3. Else the nearest clear heading at the same speed.
    let clear = !helm.blocked(&b, cmd.psi_set, v);
    let heading = if clear {
        Some(cmd.psi_set)
    } else {
        nearest_clear(cfg, &helm, &b, cmd.psi_set, v, cfg.max_turn_rad)
    };
    if let Some(a) = heading {
        // A close call: a slow-turning craft does not pass a mover close when stopping keeps
        // well clear of it (module notes).
        let stopping = || {
            let at = helm.course(cmd.psi_set, 0.0)[STOPPED];
            min(stop_margin, b.passing(at, CPA_HORIZON_S))
        };
        if helm.prm.turns_slowly()
            && can_stop
            && helm.mover_margin(&b, a, v) < min(CLOSE_CALL_M, stopping() - GAIN_M)
        {
            return (
                with_motion(cmd, cmd.psi_set, 0.0, Verdict::Stopped),
                Verdict::Stopped,
            );
        }
        if !clear {
            return (with_motion(cmd, a, v, Verdict::Turned), Verdict::Turned);
        }
        if v < planned {
            return (
                with_motion(cmd, cmd.psi_set, v, Verdict::Slowed),
                Verdict::Slowed,
            );
        }
        return (cmd, Verdict::Clear);
    }
    // 4. Slower on the planned heading.
    let mut s = 0.5 * v;
    while s >= cfg.min_speed {
        if !helm.blocked(&b, cmd.psi_set, s) {
            return (
                with_motion(cmd, cmd.psi_set, s, Verdict::Slowed),
                Verdict::Slowed,
            );
        }
        s *= 0.5;
    }
    // 5. Nothing is clear: stop, unless a mover would run into the stopped vehicle; a craft
    //    that turns slowly turns on the spot meanwhile, to where it can go.
    if can_stop {
        let psi = if helm.prm.turns_slowly() {
            turn_on_the_spot(cfg, &helm, &b, &cmd, v)
        } else {
            cmd.psi_set
        };
        return (
            with_motion(cmd, psi, 0.0, Verdict::Stopped),
            Verdict::Stopped,
        );
    }
    get_away(cmd)
}

/// The heading within ±`max_turn` of `psi`, nearest first, that is clear at `v`.
fn nearest_clear(
    cfg: &GuardConfig,
    helm: &Helm,
    b: &Believed,
    psi: f32,
    v: f32,
    max_turn: f32,
) -> Option<f32> {
    turns_from(cfg, psi, max_turn).find(|&a| !helm.blocked(b, a, v))
}

/// Headings within ±`max_turn` of `psi` (itself excepted) in steps of `turn_step_rad`, nearest
/// first, left before right.
fn turns_from(cfg: &GuardConfig, psi: f32, max_turn: f32) -> impl Iterator<Item = f32> {
    let step = max(cfg.turn_step_rad, 1e-3);
    let turns = min(max_turn / step, 64.0) as u32;
    (1..=turns).flat_map(move |k| [1.0, -1.0].map(|side| psi + side * k as f32 * step))
}

/// The clear motion nearest `psi`, all round, at `speed` and then half of it, as (heading,
/// speed); `None` if none is clear.
fn escape(
    cfg: &GuardConfig,
    helm: &Helm,
    b: &Believed,
    psi: f32,
    speed: f32,
) -> Option<(f32, f32)> {
    [speed, 0.5 * speed].into_iter().find_map(|v| {
        if !helm.blocked(b, psi, v) {
            return Some((psi, v));
        }
        nearest_clear(cfg, helm, b, psi, v, crate::math::PI).map(|a| (a, v))
    })
}

/// A mover closes in and stopping will not do: the clear heading nearest the command, all
/// round, at `speed` and then half of it; if none is clear, the heading at `speed` that
/// keeps farthest from the movers without running into anything still (next period, a little
/// faster, a clear one may be found); if that too is blocked (or `speed` is not a speed),
/// stop.
fn evade(
    cfg: &GuardConfig,
    helm: &Helm,
    b: &Believed,
    cmd: Command,
    speed: f32,
) -> (Command, Verdict) {
    match way_out(cfg, helm, b, cmd.psi_set, speed, f32::NEG_INFINITY) {
        Some((a, v)) => (with_motion(cmd, a, v, Verdict::Turned), Verdict::Turned),
        None => stopped(cmd),
    }
}

/// The way out of the movers at `speed`, as (heading, speed): the clear motion nearest `psi`
/// ([`escape`]), or else the [`least_bad`] heading at `speed` if it keeps farther from them
/// than `better_than` m; `None` if neither (or `speed` is not a speed).
fn way_out(
    cfg: &GuardConfig,
    helm: &Helm,
    b: &Believed,
    psi: f32,
    speed: f32,
    better_than: f32,
) -> Option<(f32, f32)> {
    if speed.is_nan() || speed <= 0.0 {
        return None;
    }
    escape(cfg, helm, b, psi, speed).or_else(|| {
        least_bad(cfg, helm, b, psi, speed)
            .filter(|&(_, m)| m > better_than)
            .map(|(a, _)| (a, speed))
    })
}

/// The heading, all round from `psi`, that at `speed` keeps farthest from the movers without
/// running into anything still, with that margin ([`Believed::mover_margin`]); `None` if
/// every heading runs into something still.
fn least_bad(
    cfg: &GuardConfig,
    helm: &Helm,
    b: &Believed,
    psi: f32,
    speed: f32,
) -> Option<(f32, f32)> {
    let step = max(cfg.turn_step_rad, 1e-3);
    (0..min(2.0 * crate::math::PI / step, 128.0) as u32)
        .map(|k| psi + k as f32 * step)
        .filter(|&a| !helm.blocked_still(b, a, speed))
        .map(|a| (a, helm.mover_margin(b, a, speed)))
        .fold(None, |best: Option<(f32, f32)>, (a, m)| match best {
            Some((_, bm)) if bm >= m => best,
            _ => Some((a, m)),
        })
}

/// Where a slow-turning craft stopped by the guard turns on the spot: from rest it can only
/// go nearly straight on (every heading it is offered sweeps the same arc, module notes), so
/// if straight on is blocked it would wait for ever — in a bend of a channel, at a corner of a
/// detour. It turns instead towards the planner's target (`Command::target`: the route's
/// goal-point, a ghost, or the goal), or, if the way there is blocked, the heading nearest it
/// that a craft already pointing that way could take at `v` (a straight segment). The planner
/// keeps planning; once the vehicle points where it can go, the guard lets its command out.
fn turn_on_the_spot(cfg: &GuardConfig, helm: &Helm, b: &Believed, cmd: &Command, v: f32) -> f32 {
    let Some(u) = (cmd.target - helm.p).normalized(1e-3) else {
        return cmd.psi_set;
    };
    let aim = u.angle();
    let len = reach(v, helm.prm, cfg);
    let clear = |a: f32| !b.blocked(helm.p, Vec2::from_angle(a), len, v);
    if clear(aim) {
        return aim;
    }
    turns_from(cfg, aim, crate::math::PI)
        .find(|&a| clear(a))
        .unwrap_or(aim)
}

/// `cmd` brought to a stop on its heading (the vehicle turns while it brakes).
fn stopped(cmd: Command) -> (Command, Verdict) {
    (
        with_motion(cmd, cmd.psi_set, 0.0, Verdict::Stopped),
        Verdict::Stopped,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;
    use crate::planner::{HoldReason, PidSetpoints};
    use crate::world::Obstacle;

    fn cmd(psi: f32, v: f32) -> Command {
        Command {
            psi_set: psi,
            v_set: v,
            setpoints: PidSetpoints::default(),
            mode: Mode::Transit,
            force: Vec2::ZERO,
            velocity: Vec2::new(cos(psi), sin(psi)) * v,
            target: Vec2::ZERO,
            ghost_depth: 0,
            clearance_m: f32::INFINITY,
        }
    }

    /// The verdict on `c` for a vehicle at rest at the origin at time 0, without tracks.
    fn at_rest(g: &GuardConfig, p: &Params, w: &World, c: Command) -> Verdict {
        under_way(g, p, w, Vec2::ZERO, c)
    }

    /// The verdict on `c` for a vehicle at the origin heading east with velocity `v`, at
    /// time 0, without tracks.
    fn under_way(g: &GuardConfig, p: &Params, w: &World, v: Vec2, c: Command) -> Verdict {
        check(g, p, 0, &nav(v), w, &Tracks::default(), None, c, 1.0).1
    }

    fn nav(v: Vec2) -> NavState {
        NavState {
            position: Vec2::ZERO,
            heading: 0.0,
            velocity: v,
        }
    }

    #[test]
    fn where_the_sonar_has_not_looked_it_goes_no_faster_than_it_can_stop() {
        let (g, p) = (GuardConfig::default(), Params::default());
        let map = EvidenceMap::empty();
        map.follow(Vec2::ZERO);
        let at = |g: &GuardConfig, w: &World, m: Option<&EvidenceMap>| {
            let t = Tracks::default();
            check(g, &p, 0, &nav(Vec2::ZERO), w, &t, m, cmd(0.0, 1.0), 1.0)
        };
        let open = World::new();
        let go = |m: Option<&EvidenceMap>| at(&g, &open, m);
        let beam = |look: f32, echoes: &'static [f32]| crate::sonar::Beam {
            origin: Vec2::ZERO,
            look: Vec2::from_angle(look),
            range_m: 30.0,
            blank_m: 0.0,
            echoes,
            seconded: 0,
            vehicles: 0,
        };
        // A sonar that never spoke (perception by contacts): as planned.
        assert_eq!(go(Some(&map)).1, Verdict::Clear);
        // Looked sideways only: the lookout's speed, and it says so.
        map.observe(&beam(1.5, &[]));
        let (out, v) = go(Some(&map));
        assert_eq!(
            (v, out.mode, out.v_set),
            (Verdict::Slowed, Mode::Guarded, g.lookout_mps)
        );
        // Ahead, nothing heard to 30 m: as planned.
        map.observe(&beam(0.0, &[]));
        assert_eq!(go(Some(&map)), (cmd(0.0, 1.0), Verdict::Clear));
        // The head's next pass over the sector ahead meets an echo 1.5 m off (not yet in the
        // world the guard checks): slower than planned, stopping short of it with the hull and
        // the margin.
        map.observe(&beam(-1.5, &[]));
        map.observe(&beam(0.0, &[1.5]));
        let (out, v) = go(Some(&map));
        assert_eq!(v, Verdict::Slowed);
        assert!(
            out.v_set > g.lookout_mps && out.v_set < 1.0,
            "{}",
            out.v_set
        );
        let stop = out.v_set * p.period_s + out.v_set * out.v_set / (2.0 * p.brake());
        assert!(stop + g.margin_m + p.agent_radius_m + g.hull_margin_m <= 1.5 + 0.5);
        // No map (perception by contacts), or the lookout off: as planned.
        assert_eq!(go(None).1, Verdict::Clear);
        let off = GuardConfig {
            lookout_mps: 0.0,
            ..g
        };
        assert_eq!(at(&off, &open, Some(&map)).1, Verdict::Clear);
    }

    /// A wall across +x at `x` m, as map cells every 0.5 m.
    fn wall(x: f32) -> World {
        let mut w = World::new();
        w.set_map((-20..=20).map(|k| Vec2::new(x, k as f32 * 0.5)), 0.25);
        w
    }

    #[test]
    fn a_clear_command_passes_unchanged() {
        let w = wall(10.0);
        let (out, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Clear);
        assert_eq!(out, cmd(0.0, 1.0));
    }

    #[test]
    fn heading_into_a_near_wall_turns_away_and_says_so() {
        let w = wall(1.5);
        let (out, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Turned);
        assert_eq!(out.mode, Mode::Guarded);
        assert!(out.psi_set.abs() >= 0.5, "{}", out.psi_set);
        assert!((out.velocity.norm() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn moving_at_a_wall_stops() {
        let w = wall(1.2);
        let (out, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::new(1.0, 0.0)),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Stopped);
        assert_eq!(out.v_set, 0.0);
    }

    #[test]
    fn boxed_in_slows_or_stops() {
        // Cells all round at 1.6 m: nothing is clear at 1 m/s; slow enough, ahead is clear.
        let mut w = World::new();
        w.set_map(
            (0..32).map(|k| Vec2::from_angle(k as f32 * 0.196) * 1.6),
            0.25,
        );
        let (out, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert!(matches!(v, Verdict::Slowed | Verdict::Stopped), "{v:?}");
        assert!(out.v_set <= 0.5 && out.mode == Mode::Guarded);
    }

    #[test]
    fn close_to_a_wall_it_may_still_move_away_and_along() {
        // Wall 0.6 m away (closer than hull 0.5 + cell 0.25): away and along are allowed.
        let w = wall(0.6);
        let p = Params::default();
        let g = GuardConfig::default();
        let (_, away) = check(
            &g,
            &p,
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(crate::math::PI, 1.0),
            1.0,
        );
        assert_eq!(away, Verdict::Clear);
        let (_, into) = check(
            &g,
            &p,
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 0.5),
            1.0,
        );
        assert_ne!(into, Verdict::Clear);
    }

    #[test]
    fn table_obstacles_and_agents_count_too() {
        let mut w = World::new();
        let rock = Shape::circle(Vec2::new(2.0, 0.0), 0.8).unwrap();
        w.upsert_obstacle(Obstacle::new(1, rock, 2.5, Origin::Charted, 0).unwrap())
            .unwrap();
        let (_, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Turned);
        let mut w = World::new();
        w.upsert_agent(crate::world::Agent::new(2, Vec2::new(1.5, 0.0), Vec2::ZERO, 0).unwrap())
            .unwrap();
        let (_, v) = check(
            &GuardConfig::default(),
            &Params::default(),
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Turned);
    }

    #[test]
    fn a_crossing_obstacle_is_met_where_it_will_be() {
        // 1.4 m to starboard of the track, 1 m ahead: clear if it stays (0.9 m from the track,
        // beyond hull and margin), in the way at 1.4 m/s towards the track (both get to x = 1 m
        // in a second).
        let rock = Shape::circle(Vec2::new(1.0, -1.4), 0.5).unwrap();
        let still = Obstacle::new(1, rock, 2.5, Origin::Sensed, 0).unwrap();
        let mut w = World::new();
        w.upsert_obstacle(still).unwrap();
        let g = GuardConfig::default();
        let p = Params::default();
        assert_eq!(at_rest(&g, &p, &w, cmd(0.0, 1.0)), Verdict::Clear);
        w.upsert_obstacle(still.moving(Vec2::new(0.0, 1.4)).unwrap())
            .unwrap();
        assert_ne!(at_rest(&g, &p, &w, cmd(0.0, 1.0)), Verdict::Clear);
    }

    fn mover(at: Vec2, v: Vec2, seen_ms: u64) -> World {
        let mut w = World::new();
        let o = Obstacle::new(
            1,
            Shape::circle(at, 1.0).unwrap(),
            2.5,
            Origin::Sonar,
            seen_ms,
        )
        .and_then(|o| o.moving(v))
        .unwrap();
        w.upsert_obstacle(o).unwrap();
        w
    }

    #[test]
    fn a_slow_turning_craft_is_judged_where_it_will_be_not_where_it_is_told() {
        // Heading east at 1 m/s; a mover 10 m ahead and 6 m to port crosses the track at
        // 0.6 m/s, reaching it in 10 s. Told to turn north, a craft that turns at once is
        // clear of it; the flat-fish, turning 26° in those 10 s, is still on the mover's way.
        let g = GuardConfig::default();
        let w = mover(Vec2::new(10.0, 6.0), Vec2::new(0.0, -0.6), 0);
        let moving = nav(Vec2::new(1.0, 0.0));
        let north = cmd(crate::math::PI / 2.0, 1.0);
        let quick = Params::default();
        let slow = Params {
            agent_radius_m: 2.25,
            turn_rate_rps: 0.046,
            brake_mps2: 0.1,
            ..Params::default()
        };
        let verdict =
            |p: &Params| check(&g, p, 0, &moving, &w, &Tracks::default(), None, north, 1.0).1;
        assert_eq!(verdict(&quick), Verdict::Clear);
        assert_ne!(verdict(&slow), Verdict::Clear);
    }

    #[test]
    fn a_mover_on_a_collision_course_is_evaded_not_waited_for() {
        // Crossing from starboard at 1 m/s, 6 m ahead and 6 m off the track: holding 1 m/s
        // ahead meets it in 6 s. The guard turns away at speed.
        let g = GuardConfig::default();
        let p = Params::default();
        let w = mover(Vec2::new(6.0, -6.0), Vec2::new(0.0, 1.0), 0);
        let (out, v) = check(
            &g,
            &p,
            0,
            &nav(Vec2::new(1.0, 0.0)),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(v, Verdict::Turned);
        assert!(out.v_set > 0.0 && out.psi_set.abs() > 0.2, "{out:?}");
        // Aimed straight at the vehicle: stopping is no way out either.
        let w = mover(Vec2::new(0.0, -6.0), Vec2::new(0.0, 1.0), 0);
        let (out, v) = check(
            &g,
            &p,
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 0.0),
            1.0,
        );
        assert_eq!(v, Verdict::Turned);
        assert!(out.v_set > 0.0, "{out:?}");
        // Moving away, or passing well astern: nothing to do.
        let w = mover(Vec2::new(6.0, -6.0), Vec2::new(0.0, -1.0), 0);
        assert_eq!(at_rest(&g, &p, &w, cmd(0.0, 1.0)), Verdict::Clear);
        let w = mover(Vec2::new(-8.0, -6.0), Vec2::new(0.0, 1.0), 0);
        assert_eq!(at_rest(&g, &p, &w, cmd(0.0, 1.0)), Verdict::Clear);
        // A craft that turns at 2.6°/s (the flat-fish) cannot get out of the way of one
        // meeting it head-on: it stops. (Clear passes the command, a stop, through unchanged.)
        let slow = flatfish();
        let w = mover(Vec2::new(10.0, 0.0), Vec2::new(-1.0, 0.0), 0);
        assert_eq!(at_rest(&g, &slow, &w, cmd(0.0, 0.0)), Verdict::Clear);
        // The slow craft going at `ours` among what `w` holds, commanded `c`.
        let slow_check = |w: &World, ours: Vec2, c: Command| {
            check(
                &g,
                &slow,
                0,
                &nav(ours),
                w,
                &Tracks::default(),
                None,
                c,
                1.0,
            )
        };
        // Overtaken from 6 m astern by a mover at `theirs` m/s while going at `ours`, asked
        // to stop.
        let overtaken = |theirs: f32, ours: f32| {
            let w = mover(Vec2::new(-6.0, 0.0), Vec2::new(theirs, 0.0), 0);
            slow_check(&w, Vec2::new(ours, 0.0), cmd(0.0, 0.0))
        };
        // One overtaking it at 0.45 m/s would run into it stopped: it goes on.
        let (out, v) = overtaken(0.45, 0.567);
        assert_eq!(v, Verdict::Turned, "{out:?}");
        assert!(out.v_set > 0.0, "{out:?}");
        // One overtaking it at 0.9 m/s: no motion it can make keeps clear, but going on
        // keeps it farther off than stopping would, so it goes on (the least bad).
        let (out, v) = overtaken(0.9, 0.5);
        assert_eq!(v, Verdict::Turned, "{out:?}");
        assert!(out.v_set > 0.0, "{out:?}");
        // Overtaken (0.4 m/s, from astern) with another vehicle stopped 7.3 m off the bow,
        // drifting at 1 cm/s as a stopped craft does: it is judged as if it were still. As a
        // mover, the way out of the one astern was weighed against it like any other mover,
        // and formations of flat-fish ran into their stopped mates (generated formation worlds
        // 12 and 43 with the mates' echoes left out of the map: 2 contacts in 68 → 0).
        let beside = |drift: f32| {
            let mut w = mover(Vec2::new(-6.0, 1.0), Vec2::new(0.35, -0.17), 0);
            let mate = crate::world::Agent::new(9, Vec2::new(6.5, 3.3), Vec2::new(drift, 0.0), 0);
            w.upsert_agent(mate.unwrap()).unwrap();
            slow_check(&w, Vec2::new(0.37, 0.0), cmd(0.0, 0.4))
        };
        assert_eq!(beside(-0.01), beside(0.0));
        assert_eq!(beside(0.01), beside(0.0));
    }

    #[test]
    fn a_sonar_mover_is_judged_at_its_largest_sighting() {
        use crate::sonar::{Feature, FeatureKind};
        // Crossing at 0.8 m/s to pass 1.5 m from the centre of a vehicle holding 1 m/s ahead,
        // its fits shrinking from 1.6 m to 0.3 m over four sweeps: by the last fit it clears
        // the hull; by its largest it does not.
        let mut w = World::new();
        let mut tracks = Tracks::default();
        for (k, r) in [1.6f32, 1.2, 0.7, 0.3].into_iter().enumerate() {
            let t = 9.0 * k as f32;
            let f = Feature {
                center: Vec2::new(6.0, -2.88 - 0.8 * (27.0 - t)),
                radius: r,
                kind: FeatureKind::Circle { radius: r },
                confidence: 0.9,
                time_ms: 9000 * k as u64,
                beams: 6,
                runs_on: false,
                faint: false,
            };
            let cfg = crate::guidance::TrackConfig::default();
            tracks.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
        }
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(1.0, 0.0));
        let last_fit = check(
            &g,
            &p,
            27_000,
            &moving,
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_eq!(last_fit.1, Verdict::Clear);
        let largest = check(
            &g,
            &p,
            27_000,
            &moving,
            &w,
            &tracks,
            None,
            cmd(0.0, 1.0),
            1.0,
        );
        assert_ne!(largest.1, Verdict::Clear, "{:?}", largest.0);
    }

    /// The flat-fish of seed 003 (its hull, turn rate and braking) at its recipe's cruise.
    fn flatfish() -> Params {
        Params {
            agent_radius_m: 2.25,
            turn_rate_rps: 0.046,
            brake_mps2: 0.1,
            v_max: 0.567,
            ..Params::default()
        }
    }

    /// A sonar sighting of `kind` at `center` at `time_ms`, as the extractor gives one.
    fn sighting(
        center: Vec2,
        kind: crate::sonar::FeatureKind,
        time_ms: u64,
    ) -> crate::sonar::Feature {
        let radius = match kind {
            crate::sonar::FeatureKind::Circle { radius } => radius,
            crate::sonar::FeatureKind::Rectangle { half, .. } => half.norm(),
        };
        crate::sonar::Feature {
            center,
            radius,
            kind,
            confidence: 0.2,
            time_ms,
            beams: 2,
            runs_on: false,
            faint: false,
        }
    }

    /// A world and tracks with sonar contacts `(x, y, r)` seen at 9 s; with `twice`, each also
    /// seen a sweep before in the same place (so known to stand still).
    fn sonar_contacts(contacts: &[(f32, f32, f32)], twice: bool) -> (World, Tracks) {
        use crate::sonar::FeatureKind;
        let mut w = World::new();
        let mut tracks = Tracks::default();
        let cfg = crate::guidance::TrackConfig::default();
        for time_ms in if twice {
            [0, 9000].as_slice()
        } else {
            [9000].as_slice()
        } {
            for &(x, y, r) in contacts {
                let f = sighting(Vec2::new(x, y), FeatureKind::Circle { radius: r }, *time_ms);
                tracks.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
            }
        }
        (w, tracks)
    }

    #[test]
    fn a_vehicle_sized_contact_seen_once_close_by_is_kept_off_as_far_as_it_may_have_come() {
        // An echo 2 m abeam to port, seen once at 9 s. Just seen, a turn of 45° towards it
        // passes 1.2 m off: clear. Three seconds on it may have come 1.5 m any way (half the
        // head-on speed): the same turn may meet it, and the guard holds the vehicle to
        // headings that take it no nearer.
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(0.5, 0.0));
        let towards = cmd(crate::math::PI / 4.0, 0.5);
        let (w, once) = sonar_contacts(&[(0.0, 2.0, 0.2)], false);
        let at = |now_ms, tracks: &Tracks, g: &GuardConfig| {
            check(g, &p, now_ms, &moving, &w, tracks, None, towards, 1.0)
        };
        assert_eq!(at(9_000, &once, &g).1, Verdict::Clear);
        let (out, v) = at(12_000, &once, &g);
        assert_eq!(v, Verdict::Turned, "{out:?}");
        assert!(out.psi_set <= 1e-3, "{}", out.psi_set);
        // Seen twice in one place it stands still, and off it is as before.
        let (w2, twice) = sonar_contacts(&[(0.0, 2.0, 0.2)], true);
        let still = check(&g, &p, 12_000, &moving, &w2, &twice, None, towards, 1.0);
        assert_eq!(still.1, Verdict::Clear);
        let off = GuardConfig {
            head_on_mps: 0.0,
            ..g
        };
        assert_eq!(at(12_000, &once, &off).1, Verdict::Clear);
        // Nor for a craft that turns slowly, which cannot move only away (module notes).
        let slow = Params {
            turn_rate_rps: 0.5,
            ..p
        };
        let (out, v) = check(&g, &slow, 12_000, &moving, &w, &once, None, towards, 1.0);
        assert_eq!(v, Verdict::Clear, "{out:?}");
    }

    #[test]
    fn a_vessel_that_was_closing_may_have_turned_since_it_was_last_seen() {
        // Another VideoRay, seen at 1, 5 and 10 s, crossing westward at 1 m/s 2.5 m to port.
        // Just seen, heading for where it was is clear: it will have gone on. Four seconds
        // unseen, it may have stopped and turned (its own guard acting): the same heading is
        // not. The same track keeping pace with this vehicle, a rock-sized mover, or one seen
        // twice whose velocity nothing has borne out leaves it clear.
        use crate::sonar::FeatureKind;
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(1.0, 0.0));
        let towards = cmd(crate::math::atan2(2.5, 3.0), 1.0);
        let cfg = crate::guidance::TrackConfig::default();
        let track = |xs: &[(f32, u64)], radius: f32| {
            let (mut w, mut tracks) = (World::new(), Tracks::default());
            for &(x, t) in xs {
                let f = sighting(Vec2::new(x, 2.5), FeatureKind::Circle { radius }, t);
                tracks.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
            }
            (w, tracks)
        };
        let at = |now_ms, (w, tracks): &(World, Tracks)| {
            check(&g, &p, now_ms, &moving, w, tracks, None, towards, 1.0)
        };
        let westward = [(12.0, 1_000), (8.0, 5_000), (3.0, 10_000)];
        let closing = track(&westward, 0.2);
        assert!(closing.0.obstacles()[0].velocity.x < -0.9);
        assert_eq!(at(10_000, &closing).1, Verdict::Clear);
        let (out, v) = at(14_000, &closing);
        assert_eq!(v, Verdict::Turned, "{out:?}");
        assert!(
            (out.psi_set - towards.psi_set).abs() > 0.2,
            "{}",
            out.psi_set
        );
        let pacing = [(-6.0, 1_000), (-2.0, 5_000), (3.0, 10_000)];
        assert_eq!(at(14_000, &track(&pacing, 0.2)).1, Verdict::Clear);
        assert_eq!(at(14_000, &track(&westward, 1.0)).1, Verdict::Clear);
        assert_eq!(at(14_000, &track(&westward[1..], 0.2)).1, Verdict::Clear);
    }

    #[test]
    fn inside_a_close_contacts_reach_the_wall_beyond_keeps_its_distance() {
        // A contact seen once 1.5 m astern, 4 s ago: the vehicle is inside where it may have
        // come (2.2 m), and may move only away from it — but not into the wall 1.2 m ahead,
        // which is judged by its own clearance, not by the contact's.
        let (g, p) = (GuardConfig::default(), Params::default());
        let (mut w, once) = sonar_contacts(&[(-1.5, 0.0, 0.2)], false);
        w.set_map((-20..=20).map(|k| Vec2::new(1.2, k as f32 * 0.5)), 0.25);
        let moving = nav(Vec2::new(0.5, 0.0));
        let (out, v) = check(&g, &p, 13_000, &moving, &w, &once, None, cmd(0.0, 0.5), 1.0);
        assert_ne!(v, Verdict::Clear, "{out:?}");
        // From rest, along the wall (which takes it no nearer the contact) it may go.
        let along = cmd(-crate::math::PI / 2.0, 0.5);
        let rest = nav(Vec2::ZERO);
        let (out, v) = check(&g, &p, 13_000, &rest, &w, &once, None, along, 1.0);
        assert_eq!(v, Verdict::Clear, "{out:?}");
    }

    #[test]
    fn a_contact_seen_once_dead_ahead_is_met_as_a_vehicle_on_the_reciprocal_course() {
        // A VideoRay-sized echo 8 m ahead on the track, seen once, 1 s ago: at 1 m/s each way
        // it would be here in 3.5 s. Straight on is blocked; the guard turns off the track.
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(1.0, 0.0));
        let (w, once) = sonar_contacts(&[(8.0, 0.0, 0.3)], false);
        let (out, v) = check(&g, &p, 10_000, &moving, &w, &once, None, cmd(0.0, 1.0), 1.0);
        assert_eq!(v, Verdict::Turned, "{out:?}");
        assert!(out.psi_set.abs() >= g.turn_step_rad, "{}", out.psi_set);
        // Seen twice in one place, it stands still: 8 m ahead is beyond the braking distance.
        let (w, twice) = sonar_contacts(&[(8.0, 0.0, 0.3)], true);
        assert_eq!(
            check(
                &g,
                &p,
                10_000,
                &moving,
                &w,
                &twice,
                None,
                cmd(0.0, 1.0),
                1.0
            )
            .1,
            Verdict::Clear
        );
        // Off: as before.
        let off = GuardConfig {
            head_on_mps: 0.0,
            ..g
        };
        let (w, once) = sonar_contacts(&[(8.0, 0.0, 0.3)], false);
        assert_eq!(
            check(
                &off,
                &p,
                10_000,
                &moving,
                &w,
                &once,
                None,
                cmd(0.0, 1.0),
                1.0
            )
            .1,
            Verdict::Clear
        );
    }

    #[test]
    fn a_contact_seen_once_off_the_bow_is_met_on_the_course_that_meets_ours() {
        // Seen just now 9 m off, 30° to port: on the reciprocal course it would pass 4.5 m
        // abeam, clear; a vehicle converging at 1 m/s meets us in under 5 s.
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(1.0, 0.0));
        let at = Vec2::from_angle(crate::math::PI / 6.0) * 9.0;
        let (w, once) = sonar_contacts(&[(at.x, at.y, 0.3)], false);
        let (out, v) = check(&g, &p, 10_000, &moving, &w, &once, None, cmd(0.0, 1.0), 1.0);
        assert_ne!(v, Verdict::Clear, "{out:?}");
        // The course: from the contact to where we will be, at 1 m/s.
        let u = intercept(-at, Vec2::new(1.0, 0.0), 1.0).unwrap();
        let t = (at.x / (1.0 - u.x)).abs();
        assert!((u.norm() - 1.0).abs() < 1e-4, "{u:?}");
        assert!((at + u * t - Vec2::new(t, 0.0)).norm() < 1e-3, "{u:?} {t}");
        // Outrun (it is slower and astern of the meeting point), no course meets us.
        assert_eq!(
            intercept(Vec2::new(5.0, 0.0), Vec2::new(1.0, 0.0), 0.5),
            None
        );
    }

    #[test]
    fn only_a_contact_ahead_and_standing_alone_is_taken_for_a_vehicle() {
        let (g, p) = (GuardConfig::default(), Params::default());
        let moving = nav(Vec2::new(1.0, 0.0));
        // Astern, or abeam beyond the cone: no vehicle on the reciprocal course can reach us.
        for at in [(-8.0, 0.0), (0.5, 8.0)] {
            let (w, once) = sonar_contacts(&[(at.0, at.1, 0.3)], false);
            let v = check(&g, &p, 10_000, &moving, &w, &once, None, cmd(0.0, 1.0), 1.0).1;
            assert_eq!(v, Verdict::Clear, "{at:?}");
        }
        // Against another believed obstacle (a pier's end, a rock's far face) it is structure.
        let (w, once) = sonar_contacts(&[(8.0, 0.0, 0.3), (10.0, 2.2, 1.0)], false);
        let v = check(&g, &p, 10_000, &moving, &w, &once, None, cmd(0.0, 1.0), 1.0).1;
        assert_eq!(v, Verdict::Clear);
    }

    #[test]
    fn a_short_bar_seen_once_ahead_may_be_a_vehicle_a_long_one_is_structure() {
        // Another flat-fish is fitted as a bar 3.6 m long: 8 m ahead of a flat-fish, seen
        // once, it is met as a vehicle like a round echo. A bar 8 m long is a wall's run; to a
        // VideoRay, whose fellows are 0.5 m circles, so is the short one.
        use crate::sonar::FeatureKind;
        let g = GuardConfig::default();
        let (flatfish, videoray) = (flatfish(), Params::default());
        let moving = nav(Vec2::new(0.5, 0.0));
        for (p, half, met) in [
            (&flatfish, 1.8, true),
            (&flatfish, 4.0, false),
            (&videoray, 1.8, false),
        ] {
            let mut w = World::new();
            let mut tracks = Tracks::default();
            let bar = FeatureKind::Rectangle {
                half: Vec2::new(half, 0.3),
                angle: crate::math::PI / 2.0,
            };
            let f = sighting(Vec2::new(8.0, 0.0), bar, 9000);
            let cfg = crate::guidance::TrackConfig::default();
            tracks.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
            let v = check(
                &g,
                p,
                10_000,
                &moving,
                &w,
                &tracks,
                None,
                cmd(0.0, 0.5),
                1.0,
            )
            .1;
            let r = p.agent_radius_m;
            assert_eq!(
                v != Verdict::Clear,
                met,
                "bar {half} m to a {r} m craft: {v:?}"
            );
        }
    }

    #[test]
    fn a_track_seen_twice_that_the_map_does_not_show_is_judged_as_a_shape() {
        // A box 2 m ahead, fitted twice by the tracker, where the evidence map believes
        // nothing (bench boxes seed 90: its echoes never made a cell). Still sonar tracks are
        // left to the map; this one is judged as its shape.
        let (g, p) = (GuardConfig::default(), Params::default());
        let box_ahead = Vec2::new(3.0, 0.0);
        let (mut w, tracks) = seen_at(1.0, &[(box_ahead, 0), (box_ahead, 9000)]);
        let moving = nav(Vec2::new(1.0, 0.0));
        let mut go = |cells: &[Vec2]| {
            w.set_map(cells.iter().copied(), 0.25);
            check(&g, &p, 9000, &moving, &w, &tracks, None, cmd(0.0, 1.0), 1.0).1
        };
        // A map in use, its one cell this period far astern.
        assert_ne!(go(&[Vec2::new(-20.0, 0.0)]), Verdict::Clear);
        // Once the map shows something within its extent, it speaks for the track (its cells,
        // not the fit, are what the guard meets): here a cell on the box's far face.
        assert_eq!(go(&[Vec2::new(3.9, 0.0)]), Verdict::Clear);
    }

    #[test]
    fn a_mover_unseen_for_a_while_may_be_farther_on_than_its_track_says() {
        // A rock-sized mover seen at 1, 5 and 10 s going east at 0.8 m/s, 2.1 m to starboard of
        // this vehicle's course (east at 1 m/s). Just seen, the vehicle overtakes it clear of
        // the hull. Four seconds unseen it may be up to a fifth of its way farther on (a
        // tracker rates a mover slow by that much): the same command is not clear. A track
        // whose velocity nothing has borne out is not grown.
        let (g, p) = (GuardConfig::default(), Params::default());
        let east = nav(Vec2::new(1.0, 0.0));
        let seen = |t: u64| (Vec2::new(-2.2 - 0.8 * (10.0 - t as f32 * 1e-3), -2.1), t);
        let at = |now_ms, (w, tracks): &(World, Tracks)| {
            check(&g, &p, now_ms, &east, w, tracks, None, cmd(0.0, 1.0), 1.0).1
        };
        let borne_out = seen_at(1.0, &[seen(1_000), seen(5_000), seen(10_000)]);
        assert!(borne_out.0.obstacles()[0].velocity.x > 0.7);
        assert_eq!(at(10_000, &borne_out), Verdict::Clear);
        assert_ne!(at(14_000, &borne_out), Verdict::Clear);
        let twice = seen_at(1.0, &[seen(5_000), seen(10_000)]);
        assert_eq!(at(14_000, &twice), Verdict::Clear);
    }

    /// The world and tracks after a target of `radius` m is seen at each (centre, time).
    fn seen_at(radius: f32, sightings: &[(Vec2, u64)]) -> (World, Tracks) {
        let cfg = crate::guidance::TrackConfig::default();
        let (mut w, mut tracks) = (World::new(), Tracks::default());
        for &(c, time_ms) in sightings {
            let f = sighting(c, crate::sonar::FeatureKind::Circle { radius }, time_ms);
            tracks.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
        }
        (w, tracks)
    }

    #[test]
    fn a_slow_track_not_yet_borne_out_is_met_on_its_velocity_too() {
        // The flat-fish at 0.5 m/s. A target seen 7.2 m off its track and, a sweep later,
        // 3.6 m off it: 0.4 m/s towards where the craft will be in 8 s. Too slow to be given a
        // velocity before a third sighting bears it out, it is still in the table; the guard
        // meets it moving all the same, a slow-turning craft's and a VideoRay's — until that
        // third sighting is overdue.
        let g = GuardConfig::default();
        let flatfish = flatfish();
        let moving = nav(Vec2::new(0.5, 0.0));
        let (w, tracks) = seen_at(
            0.3,
            &[(Vec2::new(4.0, 7.2), 0), (Vec2::new(4.0, 3.6), 9000)],
        );
        let o = w.obstacles()[0];
        assert_eq!(o.velocity, Vec2::ZERO, "not yet given a velocity");
        let v = tracks.tentative(o.id, || true).unwrap();
        assert!((v - Vec2::new(0.0, -0.4)).norm() < 0.05, "{v:?}");
        let go = cmd(0.0, 0.5);
        let (out, verdict) = check(&g, &flatfish, 10_000, &moving, &w, &tracks, None, go, 0.567);
        assert_ne!(verdict, Verdict::Clear, "{out:?}");
        let videoray = Params::default();
        let v = check(&g, &videoray, 10_000, &moving, &w, &tracks, None, go, 1.0).1;
        assert_ne!(v, Verdict::Clear);
        // The same, seen 4.4 m farther off, judged a sweep later: where its velocity would
        // put it now it is again on the way, but its third sighting is overdue (a rock's
        // wander, not a mover) and it is met still.
        let (w, tracks) = seen_at(
            0.3,
            &[(Vec2::new(4.0, 11.6), 0), (Vec2::new(4.0, 8.0), 9000)],
        );
        let overdue = 9000 + (CPA_HORIZON_S * 1000.0) as u64 + 100;
        let at = |prm: &Params, now_ms: u64| {
            check(&g, prm, now_ms, &moving, &w, &tracks, None, go, 0.567).1
        };
        for prm in [&flatfish, &videoray] {
            assert_eq!(at(prm, overdue), Verdict::Clear);
            assert_ne!(at(prm, overdue - 200), Verdict::Clear, "a sweep since: met");
        }
    }

    #[test]
    fn a_mover_is_judged_where_it_is_now_not_where_it_was_seen() {
        // Seen 8 s ago 14 m to starboard heading for the track at 1 m/s: now 6 m off it.
        let g = GuardConfig::default();
        let p = Params::default();
        let w = mover(Vec2::new(6.0, -14.0), Vec2::new(0.0, 1.0), 0);
        assert_ne!(
            check(
                &g,
                &p,
                8000,
                &nav(Vec2::ZERO),
                &w,
                &Tracks::default(),
                None,
                cmd(0.0, 1.0),
                1.0
            )
            .1,
            Verdict::Clear
        );
        // The same sighting, had it been made just now, is no threat within the horizon.
        assert_eq!(at_rest(&g, &p, &w, cmd(0.0, 1.0)), Verdict::Clear);
    }

    #[test]
    fn a_slow_turning_craft_stopped_by_the_guard_turns_on_the_spot_towards_its_target() {
        // The flat-fish (seed 003) at rest, a wall 2.95 m ahead that ends at y = 2: straight on
        // is blocked and, from rest, so is every heading it could turn to while moving.
        let prm = flatfish();
        let mut w = World::new();
        w.set_map((-20..=4).map(|k| Vec2::new(2.95, k as f32 * 0.5)), 0.25);
        let mut c = cmd(0.0, 0.5);
        c.target = Vec2::new(10.0, 8.0);
        let g = GuardConfig::default();
        let (out, v) = check(
            &g,
            &prm,
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            c,
            1.0,
        );
        assert_eq!(v, Verdict::Stopped);
        assert_eq!((out.v_set, out.mode), (0.0, Mode::Guarded));
        // The target's bearing (39°) runs into the wall too: the nearest heading past its end.
        let deg = out.psi_set.to_degrees();
        assert!((60.0..=100.0).contains(&deg), "turns to {deg}°");
        // Pointing there, it may go.
        let turned = NavState {
            heading: out.psi_set,
            ..nav(Vec2::ZERO)
        };
        let go = cmd(out.psi_set, 0.5);
        assert_eq!(
            check(&g, &prm, 0, &turned, &w, &Tracks::default(), None, go, 1.0).1,
            Verdict::Clear
        );
        // Without a target apart from where it is, it keeps the planner's heading.
        let (out, _) = check(
            &g,
            &prm,
            0,
            &nav(Vec2::ZERO),
            &w,
            &Tracks::default(),
            None,
            cmd(0.0, 0.5),
            1.0,
        );
        assert_eq!(out.psi_set, 0.0);
    }

    #[test]
    fn a_slow_turning_craft_skidding_towards_a_wall_it_runs_along_is_guarded() {
        // The flat-fish runs east at 0.5 m/s along a wall 0.3 m beyond its hull to starboard.
        // Straight on keeps that clearance; skidding to starboard at 7 cm/s, as it does coming
        // out of a turn, it would cover the 0.3 m before it could stop.
        let prm = flatfish();
        let mut w = World::new();
        let y = -(prm.agent_radius_m + 0.3);
        w.set_map((-4..=40).map(|k| Vec2::new(k as f32 * 0.5, y)), 0.25);
        let g = GuardConfig::default();
        let verdict = |sway: f32| under_way(&g, &prm, &w, Vec2::new(0.5, sway), cmd(0.0, 0.5));
        assert_eq!(verdict(0.0), Verdict::Clear);
        assert_eq!(verdict(0.07), Verdict::Clear, "skidding away from it");
        assert_ne!(verdict(-0.07), Verdict::Clear);
    }

    #[test]
    fn a_slow_turning_craft_meets_a_reported_mover_over_a_longer_horizon_than_a_sonar_track() {
        // The flat-fish heads east at 0.65 m/s; a mover crossing north at 1 m/s reaches its
        // track 14.5 s from now, just where it will be. Within 10 s they stay 5.3 m apart, more
        // than hull and mover and a close call ([`CLOSE_CALL_M`]); a contact the host reports
        // is judged over 15 s, a sonar track (whose velocity is a few fits old) over 10.
        let prm = Params {
            v_max: 0.65,
            ..flatfish()
        };
        let g = GuardConfig::default();
        let verdict = |origin: Origin| {
            let mut w = World::new();
            let o = Obstacle::new(
                1,
                Shape::circle(Vec2::new(9.4, -14.5), 1.0).unwrap(),
                2.5,
                origin,
                0,
            )
            .and_then(|o| o.moving(Vec2::new(0.0, 1.0)))
            .unwrap();
            w.upsert_obstacle(o).unwrap();
            under_way(&g, &prm, &w, Vec2::new(0.65, 0.0), cmd(0.0, 0.65))
        };
        assert_eq!(verdict(Origin::Sonar), Verdict::Clear);
        assert_ne!(verdict(Origin::Sensed), Verdict::Clear);
    }

    #[test]
    fn a_slow_turning_craft_stops_rather_than_pass_close_ahead_of_a_crossing_mover() {
        // The flat-fish heads east at 0.65 m/s. A sonar mover crossing north 9 m ahead passes
        // in front of it by less than a metre beyond the hull if it goes on, by 3.6 m if it
        // stops: it stops. A slower one, further off, would pass astern of it going on but
        // run into it stopped, however long it took: it goes on.
        let prm = Params {
            v_max: 0.65,
            ..flatfish()
        };
        let g = GuardConfig::default();
        let verdict = |at: Vec2, v: Vec2| {
            let w = mover(at, v, 0);
            under_way(&g, &prm, &w, Vec2::new(0.65, 0.0), cmd(0.0, 0.65))
        };
        assert_eq!(
            verdict(Vec2::new(9.0, -7.0), Vec2::new(0.0, 1.0)),
            Verdict::Stopped
        );
        assert_eq!(
            verdict(Vec2::new(5.0, -11.0), Vec2::new(0.0, 0.8)),
            Verdict::Clear
        );
    }

    #[test]
    fn a_slow_turning_craft_creeping_on_is_at_rest_to_the_guard() {
        // The flat-fish with a wall 2.35 m ahead of its centre, within its hull and margin:
        // going straight on at all is blocked. Its drag takes tens of seconds over the last
        // centimetres per second, and braking on the planner's heading it waited them out.
        let prm = flatfish();
        let mut w = World::new();
        w.set_map((-20..=4).map(|k| Vec2::new(2.6, k as f32 * 0.5)), 0.25);
        let mut c = cmd(0.0, 0.5);
        c.target = Vec2::new(10.0, 8.0);
        let g = GuardConfig::default();
        let at = |u: f32| {
            let nav = nav(Vec2::new(u, 0.0));
            let (out, v) = check(&g, &prm, 0, &nav, &w, &Tracks::default(), None, c, 1.0);
            assert_eq!((v, out.v_set), (Verdict::Stopped, 0.0), "at {u} m/s");
            out.psi_set
        };
        let turn = at(0.0);
        assert!(turn > 0.5, "turns to {}°", turn.to_degrees());
        // Creeping at 2 cm/s it turns as at rest; at 0.2 m/s it brakes on the planner's heading.
        assert_eq!(at(0.02), turn);
        assert_eq!(at(0.2), 0.0);
    }

    #[test]
    fn holds_and_a_disabled_guard_pass_through() {
        let w = wall(0.8);
        let hold = Command::hold(HoldReason::StaleNav, 0.0);
        assert_eq!(
            check(
                &GuardConfig::default(),
                &Params::default(),
                0,
                &nav(Vec2::ZERO),
                &w,
                &Tracks::default(),
                None,
                hold,
                1.0
            )
            .0,
            hold
        );
        let off = GuardConfig {
            enabled: false,
            ..GuardConfig::default()
        };
        assert_eq!(
            check(
                &off,
                &Params::default(),
                0,
                &nav(Vec2::ZERO),
                &w,
                &Tracks::default(),
                None,
                cmd(0.0, 1.0),
                1.0
            )
            .1,
            Verdict::Clear
        );
    }

    #[test]
    fn a_movers_old_place_in_the_table_does_not_loosen_the_keep_off_from_a_wall() {
        // A sonar track rated as moving away north, still in the table where it was seen, 0.2 m
        // from the vehicle; a wall ahead that the motion would bring within the hull but not
        // within 0.2 m. The mover is met on its closest approach; the wall by the hull.
        let (g, p) = (GuardConfig::default(), Params::default());
        let hull = p.agent_radius_m + g.hull_margin(&p);
        let r_map = core::f32::consts::FRAC_1_SQRT_2 * 0.5;
        let stop_at = reach(0.5, &p, &g);
        let mut w = wall(stop_at + r_map + 0.5 * (hull + 0.2));
        let old = Obstacle::new(
            1,
            Shape::circle(Vec2::new(-1.2, 0.0), 1.0).unwrap(),
            2.5,
            Origin::Sonar,
            0,
        )
        .and_then(|o| o.moving(Vec2::new(0.0, 1.0)))
        .unwrap();
        w.upsert_obstacle(old).unwrap();
        assert_ne!(at_rest(&g, &p, &w, cmd(0.0, 0.5)), Verdict::Clear);
    }

    #[test]
    fn a_slow_turning_craft_judges_a_mate_ahead_where_it_is_as_well() {
        // A mate 5.5 m ahead pulling away at 0.8 m/s: on its closest approach it is clear, but
        // its guard may stop it, and the flat-fish could not stop short of it.
        let g = GuardConfig::default();
        let mut w = World::new();
        let mate = crate::world::Agent::new(2, Vec2::new(5.5, 0.0), Vec2::new(0.8, 0.0), 0);
        w.upsert_agent(mate.unwrap()).unwrap();
        let verdict = |prm: &Params| under_way(&g, prm, &w, Vec2::new(0.567, 0.0), cmd(0.0, 0.567));
        assert_ne!(verdict(&flatfish()), Verdict::Clear);
        let turns_at_once = Params {
            turn_rate_rps: 0.0,
            ..flatfish()
        };
        assert_eq!(verdict(&turns_at_once), Verdict::Clear);
    }
}
