//! Sonar features into the obstacle table: association across sweeps, a velocity per track
//! (alpha–beta filter), ids, and the table's eviction policy.
//!
//! The extractor (`crate::sonar`) emits a feature per sweep per obstacle, without identity.
//!
//! **Association.** Each sensed obstacle in the table has a track: a centre, a velocity
//! estimate and the time of its last update. A feature belongs to the nearest track whose
//! predicted centre lies within the gate: the larger of the two radii + `gate_m`, plus an
//! allowance for motion since the track's last update that depends on what is known of it:
//! - a **rated** track (its velocity has been estimated) is predicted on that velocity, and the
//!   allowance is a quarter of the predicted motion plus a slow manoeuvre (0.1 m/s): a rock
//!   seen twice in one place does not jump to the next echo a few metres off (a mover passing
//!   it, a neighbouring box), and a wall's echoes, which "move" differently from sweep to
//!   sweep as the vehicle runs along it, start new tracks rather than make one a phantom mover;
//! - an unrated track may have moved at up to `gate_speed_mps` in any direction, once at least
//!   `revisit_ms` have passed: a scanning head sees a target again only a sweep later, so a
//!   feature a second or two after a track's update is a *different* object further round the
//!   sweep, and must not be pulled into a neighbour's gate. The allowance grows for up to two
//!   sweeps (`UNRATED_GAP_S`), so a target missed on one sweep is still gated when it is seen
//!   again.
//!
//! The feature then updates that obstacle (the new feature's shape; refreshed `seen_ms`);
//! otherwise it becomes a new sensed obstacle with a fresh id from [`SONAR_ID_BASE`] upwards.
//! (Nearest-neighbour association with an unrated gate of 1 m/s × a 9 s sweep let a box's
//! sighting take over the track of another box 8 m away, in generated box fields: the tight
//! gate of rated tracks is what keeps such hand-overs to the first sweep.)
//!
//! **Hand-overs.** A track seen once gates anything within a sweep's travel, so a mover seen
//! for the first time a few metres from a rock seen once can take the rock's track, and the
//! jump becomes a velocity pointing from the rock to the mover: 50–90° off the mover's course
//! in the generated crossing worlds, where the guard then met it in the wrong place. The sweep
//! that brought the mover usually shows the rock again where it was: a sighting within a sweep
//! of such a jump (two `revisit_ms`) that lands on the track's first place, nearer it than the
//! place it jumped to, hands the track back (`Tracks::hand_back`): the track forgets the
//! velocity and stays, seen once, at the mover's place, and the sighting opens a track for the
//! rock. (Crossing and head-on worlds, seeds 0–599 × 3 strategies: contacts 64 → 56.) When the
//! mover had been seen once a sweep before, and its track's unrated gate holds the jump, the
//! jump is that track's second look instead: the mover gets its velocity from the two, and the
//! rock's track goes back to its first place for the sighting to update. Left to the wide
//! gate, the rock's sighting went to the mover's first track as a 1 m/s "mover", the real one
//! stayed a still contact seen once, and a flat-fish at 0.85 m/s met it (crossing seed 16).
//! Flat-fish with its recipe, seeds 0–67: 675 → 678 of 816 (5 gained, 2 lost), 1 → 1
//! contact; at 0.85 m/s, seeds 0–33: 352 → 356, contacts 5 → 3 (2 gone, none new). VideoRay,
//! crossing and head-on × 3 strategies, seeds 0–199: contacts 16 → 15 (2 gone, 1 new),
//! successes 1 158 → 1 158; seeds 200–399, run for run the same; the other ten families ×
//! 3, seeds 0–49: no contact, 1 446 → 1 449 of 1 500 (`hil bench-diff`).
//!
//! *The nearer look.* The other way round, the head passes a rock first and the mover a moment
//! later in the same sweep: the mover's track, seen once, takes the rock as its second look (a
//! velocity from the mover's first place to the rock, the wrong way), and the mover's own
//! sighting, outside that rated track's tight gate, opens a still one. In flat-fish crossing
//! 69 the mover was rated right only a sweep later, 9 m off, too late for a craft that turns
//! at 2.6°/s, and ran into it. So a sighting no track gates, within a pass of the head
//! (`revisit_ms`) of such a jump, that lands nearer the track's first place than the jump
//! did and within its unrated gate from there, is its second look instead
//! ([`Tracks::nearer_look`]): the track goes back to its first sighting and is rated on this
//! one, and the jump opens a track of its own, seen once. Only for a jump over a sweep or so
//! ([`MAX_GAP_S`]): a track seen once and unseen for longer is as likely a rock the head
//! missed, whose wide gate reaches the next rocks. Without that limit it fired on jumps of
//! 17–20 m between rocks in the flat-fish's clutter worlds, and `--trial 1` lost six of them
//! (all near their time limit). The flat-fish with its recipe (`cargo hil bench --models
//! flatfish --params hil/recipes/flatfish.toml --seeds 170`), against the code before: trial
//! 0, 1 828 → 1 829 of 2 040, contacts 1 → 0 (crossing 69 gone); `--trial 1`, 1 821 → 1 817
//! (four clutter and rock worlds at 3–3.7 × their reference time before timed out), contacts
//! 6 → 6, the same runs.
//!
//! **Velocity.** An alpha–beta filter per track (e.g. Bar-Shalom & Li, *Estimation and
//! Tracking*, §5.3): with the residual r = z − (x + v·Δt), x ← x + v·Δt + α·r and
//! v ← v + (β/Δt)·r; the second sighting starts it with the two-point difference (gain 1 in
//! place of β). Updates less than `min_update_ms` apart leave the velocity alone, since a
//! short Δt turns centre noise into speed, and the correction is spread over at least half a
//! sweep (Δt taken as no less than `revisit_ms`): a fit is a metre or so off, another face of
//! the target, and a vehicle that turns meets a target twice within a second or two. Over the
//! true gap, such a second look made a 0.84 m/s mover 1.5 m/s, and the guard met it 5 m from
//! where it was (bench crossing and head-on worlds, seeds 0–599 × 3 strategies: contacts
//! 99 → 81; on seeds 200–599, not looked at before, 64 → 49).
//!
//! The velocity is handed to the planner (`Obstacle::velocity`) once a track has `min_hits`
//! updates (and, if `min_steady` > 0, that many of them after the velocity was set landing
//! where it predicted), has moved farther than its own radius (at least 1 m) since it was
//! first seen, and is faster than `min_speed_mps`. With a 9 s sweep a target crossing at
//! 1 m/s is often seen only twice before it reaches the track (generated crossing worlds, own
//! sonar): the velocity is used from the second sighting, and the guard meets it where it
//! will be (`crate::guidance::guard`).
//!
//! The defaults are measured, not derived: α = 1 (the obstacle is where the sonar saw it last),
//! β = 1/3 (the velocity closes a third of its error per sweep), a 0.3 m/s floor (confirmed
//! below 0.5 m/s: "Slow movers" below), two hits, a confidence floor of 0.15 (two strong
//! beams, the extractor's floor: a 1 m target at 20 m is seen by three or four beams of 1.8°,
//! and with a floor of 0.5 such movers were dropped until they were 10 m away; another
//! VideoRay is never seen on more than two). As the
//! vehicle passes a still rock the sonar sees other faces of it and the fitted centre wanders,
//! at up to about 0.3 m/s; reported as motion and extrapolated over the planning horizon, those
//! speeds, and equally a smoothed (α < 1) centre that lags the improving fits, led the VideoRay
//! into rocks of the random-clutter scenario under link faults (`hil/tests/e2e.rs`). A target
//! crossing at 0.8 m/s is tracked within 0.1 m/s after 8 sweeps (`hil/tests/tracker.rs`).
//! Slower sonar targets are planned as still; contacts from the host carry their own
//! velocity. Speeds are capped at `max_speed_mps`.
//!
//! **Slow movers.** The floor was 0.5 m/s: a diver or a drifting craft at 0.3–0.5 m/s was
//! then a still rock to the guard, which let it run into a vehicle that had slowed or stopped
//! beside it (navfn, seeds 0–199: 9 of its 13 crossing contacts). Below 0.5 m/s
//! ([`SURE_MPS`]) a velocity is used once a sighting has landed where it predicted (`steady`
//! ≥ 1): a rock's fits wander at such speeds, but not where a velocity says. Bench crossing and
//! head-on worlds, seeds 0–599 × 3 strategies, contacts: 99 before this round, 81 with the
//! half-sweep correction above, 64 with both. Without the confirmation the slow floor gave 54,
//! but rocks' wander made phantom movers: the flat-fish, whose guard stops for a mover,
//! reached 270 of 408 worlds against 285, and the shipped survey took 100 s longer, detouring
//! round a rock. The guard meets such a velocity before it is borne out, until the sighting
//! that should bear it out is overdue ([`Tracks::tentative`], `crate::guidance::guard`, "Slow
//! tracks"); the planner does not.
//!
//! *Measured and left as it is.* A slow mover's sightings wander round its course: one crossing
//! at 0.41 m/s was seen four times, a sweep apart, and its third sighting fell 3.6 m from where
//! the filter's two-point start put it, so its velocity was used only from the fourth, 1.5 s
//! before it met a flat-fish. The mean velocity since the first sighting, used from the third
//! when it spans two sweeps and points within 45° of the filter's: crossing and head-on worlds
//! × 3 strategies, seeds 0–599, contacts 55 → 53 (7 gone, 5 new); the flat-fish with its
//! recipe, seeds 0–135, 1 217 → 1 205 successes and 12 → 11 contacts. A track predicted over a
//! whole gap of up to 20 s, not 10 (a mover missed for two sweeps was not gated by its own
//! track, and came back as a new, still one): 55 → 55.
//!
//! **Once a mover.** A slow mover's next sighting may land outside the gate of its prediction
//! all the same (its fits wander by a metre): `steady` falls to 0, its velocity is no longer
//! used, and β pulls it towards the miss. A mover crossing at 0.39 m/s, borne out at its 13th
//! sighting, missed at its 14th (1.8 m off the 4 s prediction; 0.43 → 0.30 m/s): still to the
//! planner, and under `TENTATIVE_MPS` to the guard too, so a navfn VideoRay turned towards it
//! 3 m off and was run into (crossing 84). A track that was once a mover the structure rule
//! keeps ("Structure does not move" below: borne out twice in a row, coming on;
//! [`Track::borne`]) is a slow track to the guard from [`BORNE_MPS`] rather than
//! `TENTATIVE_MPS` ([`Tracks::tentative`]); the planner's field takes it for still until a
//! sighting bears it out again. All families, seeds 0–199, against the code before: VPF
//! 2 396 → 2 397 of 2 400, no contact either way; multipoint 2 378 → 2 375 (channels and wall
//! gaps: 5 lost, 2 gained, slow runs near their time limit), contacts 1 → 1; navfn 2 225 →
//! 2 227, contacts 1 → 0 (that one gone). *Tried first:* the same at any speed (a fast track
//! the structure rule had made still, too): the same contact gone, but wall fragments that a
//! channel's bend brings towards the vehicle were met as movers — channels' median guard
//! periods per run 60 → 99, multipoint 2 378 → 2 372; borne out once at any heading, VPF
//! channels 199 → 197 of 200; coming on faster than this vehicle goes away, 199 → 197 too.
//!
//! **Drifting.** A slow mover's filter speed hovers about the 0.3 m/s floor, and a miss
//! clears `steady`: the bench's crossing movers at 0.30–0.41 m/s were still to the flat-fish's
//! planner and guard after eight sightings, about 20 m from the first (crossing 106 and 141
//! at `--trial 1`), and ran into it while it turned out of their way. No rock's fits wander
//! that far from its first sighting: a track [`FAR_SIZES`] times its size (at least 1 m) from
//! it, whose filter says at least [`BORNE_MPS`], is met by a slow-turning craft's guard on that
//! velocity, borne out or not, if it stands alone — a wall's fragment slides along the wall as
//! the vehicle passes, and against the wall it is not alone (`crate::guidance::guard`, "Slow
//! tracks"; without that test the flat-fish's guard met channels' fragments, 20 % more guard
//! periods there, and lost two of 34 channels). Flat-fish with its recipe, crossing and head-on,
//! contacts: seeds 0–101 at `--trial 1`, 5 → 4; 102–169, 5 → 4; 170–237, 4 → 1; 170–237 at
//! `--trial 2`, 2 → 2; seeds 0–169 at trial 0, 2 → 2: 18 → 13 (6 gone, 1 new), successes
//! 926 → 931 of 952; all families, seeds 0–169, at trial 0 1 792 → 1 792 (contacts 2 → 2),
//! at trial 1 1 779 → 1 781 (10 → 8). The VideoRay's guard does not ask it
//! (`crate::guidance::guard`, "Slow tracks"). Twice its size rather than three times:
//! crossing and head-on at `--trial 1`, seeds 0–169, contacts 8 → 7 (crossing 1 gone, whose
//! mover was borne out three times at 0.27–0.29 m/s, under the floor); not worth a looser
//! test of rocks.
//!
//! *Movers passing a rock, tried and not kept.* A mover passing a rock is one blob with it for
//! a sweep or two: its fit is pulled off its course (1.8 m, for one at 0.45 m/s borne out three
//! times) and the map's rock runs on through it, so the miss clears `steady` and the sighting
//! counts as structure, and the rock's track takes the blob (generated crossing seeds 39, and
//! 190 at `--trial 1`: the mover came out of the rock believed still, into the VideoRay).
//! Halving `steady` on a miss and keeping a moving track's velocity whatever runs on through
//! it kept those movers (with the map's wakes gone, `crate::sonar::wakes`: VPF, all families,
//! seeds 0–199 × 2 trials, contacts 2 → 1), but also kept the wall fragments of a channel's
//! bend that had once been rated as moving: no longer structure, their echoes were left out of
//! the map as a mover's, and a multipoint VideoRay grazed the corner they hid (channel 68).
//!
//! **Hasty looks.** A vehicle that turns meets a target twice within a second or two. A track
//! seen once that took such a second look was rated on it — a velocity of the fits' wander
//! over the half-sweep floor, about 0.25 m/s, which is "still" — and a rated track's tight
//! gate then missed its next sighting a sweep later, wherever the target had gone: two
//! VideoRays circling each other at 2–6 m saw each other as a string of still tracks, each
//! seen twice, and met (generated head-on worlds, multipoint). A track no larger than
//! [`HASTY_DM`] (0.5 m: another VideoRay, not a rock or a crossing mover) stays seen once after
//! such a look, where it was seen last, and its next sighting a sweep later rates it. Crossing
//! and head-on worlds × 3 strategies, seeds 0–599: contacts 57 → 55 (two navfn head-on gone,
//! none new), successes 3 478 → 3 480; channel, harbour and wall-gap worlds, seeds 0–99:
//! 824 → 824, no contact; clutter and boxes, seeds 0–199: 1 148 → 1 149, contacts 1 → 1; the
//! flat-fish with its recipe, all families, seeds 0–33: unchanged, row for row. With
//! structure's fragments included (they count no size) channels lost 6 of 300. For every size (rocks too, whose second look then keeps the wide unrated
//! gate) it was tried before: all families, seeds 0–199 × 3, contacts 20 → 19 but navfn's
//! clutter 183 → 173, and a new box contact on seeds 200–349.
//!
//! **Glimpses.** Another VideoRay, narrower than the 3° beam, is on one 1.8° ping as often as
//! on two, and a feature needs two: two VideoRays meeting head-on each saw the other once, on
//! two beams at 26 m, and a sweep later, at 8 m, on one beam only (a return of 210,
//! saturating), so each took the other for a still rock and both turned the same way round
//! it (generated head-on seed 93). The extractor lets such a strong single beam out as a
//! *glimpse* ([`crate::sonar::GLIMPSE_INTENSITY`]: one beam, confidence 0), which alone never
//! opens a track — one beam cannot tell a small target from a spurious one (but see "Faint
//! pairs") — and is the second look
//! at a compact track seen once: taken when it lies on nothing believed (a rock's edge on one
//! beam is that rock), a sweep or more after the sighting, within that track's unrated gate
//! and no other's. One beam in two tracks' gates is held, not guessed, until the head has
//! looked at them again (at most `revisit_ms`): a candidate seen again where it was is still,
//! and the glimpse was the other (head-on seed 111: another VideoRay seen once 29 m off and a
//! rock seen once 14 m off both gated a glimpse 13 m off; dropped, the vehicle stayed a
//! "still rock" and the two met 8 s later).
//! Only a track no larger than [`GLIMPSED_DM`] takes one: for every compact track, multipoint
//! lost 9 of 400 clutter and box worlds (a glimpse near a rock seen once gave it a velocity).
//! Crossing and head-on worlds × 3 strategies, seeds 0–199: contacts 19 → 17, none new;
//! successes 1 154 → 1 157; clutter and boxes × 3, 1 149 → 1 143 of 1 200, 1 → 1 contact.
//!
//! **Faint pairs.** What was left of the head-on contacts was the other VideoRay never seen on
//! two beams, nor strongly on one: in each of the eight of the bench's second trial
//! (`--trial 1`, seeds 200–599 × 3 strategies), re-flown with the extractor's echoes logged,
//! at least one of the two had seen the other on one beam a sweep (3.2 s) apart, at 18 → 12 →
//! 6 m, 6–7 s before they met, and each beam was dropped as a lone echo. Such a beam now
//! leaves the extractor as a *faint* sighting (`crate::sonar::Feature::faint`, a mean of at
//! least `crate::sonar::FAINT_INTENSITY`); two a sweep or two apart, at a vehicle's speed, on
//! a collision course, open a mover of [`FAINT_RADIUS_M`] with their velocity
//! ([`super::faint`]), and it takes its later faint sightings as its next looks (only a track
//! a pair opened does: a crossing mover's faint fragments moved its rated track off course).
//! A glimpse that is no track's second look may pair too (head-on 551: the first sighting was
//! a glimpse). It goes when nothing has borne it out for two sweeps (`Tracks::lapse`), and a
//! slow-turning craft opens none ([`super::faint`], "Spurious pairs"). `hil bench-diff`
//! against the code before: crossing and head-on × 3 strategies, seeds 200–399, contacts
//! 2 → 2 (multipoint head-on 292 and 381 gone; multipoint 384 and navfn 247 new, pairs that
//! saw each other first at 2 m, with no pair formed), successes 1 198 → 1 198; seeds
//! 400–599 at `--trial 1`, contacts 8 → 1 (seven gone, none new: VPF head-on 403 is left),
//! successes 1 190 → 1 199. VPF, all families, seeds 0–199: 2 398 → 2 395 (4 lost, 1
//! gained), no contact either way. Multipoint and navfn, all families, seeds 0–199: 2 376 →
//! 2 377 and 2 233 → 2 226 (16 and 21 gained, 15 and 28 lost), contacts 1 → 2 and 1 → 0
//! (two head-on gone; a multipoint head-on and a crossing mover new), median time ÷ reference
//! 1.55 → 1.63 and 1.75 → 1.82: the phantoms that remain cost time. The flat-fish with its
//! recipe, seeds 0–33: unchanged, run for run.
//! Built first without the floor on the mean, the simulated sonar's spurious echoes paired
//! too, a phantom mover every 20–50 s under way: seeds 200–399, multipoint 398 → 400 (contacts
//! 2 → 0), but VPF 400 → 398 (0 → 2) and navfn 400 → 386 (0 → 2; a navfn pair made 49 phantoms
//! in 900 s of head-on 213 and wandered). *Tried and not kept:* a shorter `revisit_ms`
//! (1 600 ms, half the bench's 3.2 s sweep, instead of 4 000): on the same worlds VPF 400 → 399
//! (a new head-on contact), navfn 400 → 399, multipoint unchanged; again (2026-12-07) on
//! crossing, head-on and formation × 3 strategies, seeds 0–199: 1 795 → 1 792 of 1 800,
//! contacts 1 → 2 (a navfn crossing mover new).
//!
//! **Structure does not move.** A feature longer than `max_mover_half_m` (an elongated fit of
//! a wall or a pier) is never given a velocity: running along a channel, each sweep fits the
//! wall abeam of the vehicle, and a track that follows those fits "moves" with the vehicle. In
//! the bench's channels such phantom movers, met by the guard at their closest approach, drove
//! the VideoRay into the opposite wall (`hil bench`, own sonar: two collisions). A wall met at
//! a grazing angle returns only a short run of echoes, fitted as a compact circle of 2–3 m:
//! so a feature the evidence map's believed structure runs on through, on both sides
//! ([`Feature::runs_on`]), is structure too. Without it, such fragments "moving" at the
//! vehicle's speed turned it back in its channel, and the route layer then led it through a
//! stretch of wall the sonar had only grazed (bench channels × 3 strategies, contacts: seeds
//! 0–299 28 → 26, seeds 300–599 42 → 30; all families, seeds 0–99: 23 → 20).
//! But a mover leaves believed cells behind it (its echoes of a sweep or two ago, until the
//! map's free space clears them), and as it closes on the vehicle its next sighting runs on
//! from them: a 2 m mover crossing at 0.85 m/s, borne out twice, was made still by its fifth
//! sighting 7 m off, and a multipoint VideoRay steered under it (generated crossing seed 120).
//! So a track whose last [`BORNE_OUT`] sightings (two in a row) landed where its velocity put
//! them, and which comes towards where the vehicle is at [`TENTATIVE_MPS`] or more, keeps
//! that velocity when structure runs on from it. A wall's fragment abeam "moves" with the
//! vehicle, alongside it, not towards it (a long fit still never moves).
//! `hil bench-diff` against the code before, all families, seeds 0–199: VPF 2 395 → 2 396 of
//! 2 400, no contact either way; multipoint 2 377 → 2 378, contacts 2 → 1 (that one gone);
//! navfn 2 226 → 2 225, contacts 0 → 1 (crossing 84: the rule kept a 0.43 m/s mover moving
//! at 83 s, and at 331 s, on another course, a 0.39 m/s mover believed still — "Slow movers"
//! — ran into the stopped vehicle). Channels, where keeping every moving track's velocity
//! (above, "Movers passing a rock") lost a corner: VPF 197 → 199, multipoint 197 → 196,
//! navfn 94 → 92. The flat-fish with its recipe, seeds 0–33: 333 → 331 of 408 (4 lost, 2
//! gained), no contact. Crossing and head-on × 3 strategies, seeds 200–399, and 400–599 at
//! `--trial 1`: run for run the same.
//! Without the test of coming towards the vehicle (any track borne out twice) it measured as
//! well (all families × 3, seeds 0–199: 2 395, 2 378 and 2 232, contacts 0, 1 and 0), but a
//! wall's fragment keeping pace abeam would move. Coming towards it *relative* to the vehicle
//! does not keep crossing 120's mover: that VideoRay was running from it at 0.7 m/s when it
//! was made still.
//!
//! *A circle wider than a vessel* is structure too (2026-12-06): a wall's run of echoes at a
//! bend or a grazing angle may be fitted as a circle, and one of 10 m radius, tracked along a
//! channel's wall at the VideoRay's 1 m/s, was met by its guard as a mover; the evasion ran the
//! vehicle into the opposite wall, which the map did not yet believe (held-out channel 2065,
//! a graze of 0.006 m). A circle of radius over `max_mover_half_m` (3 m; another flat-fish is
//! 1.8 m) now counts as a long bar does. VPF, all families (`cargo hil bench --first-seed
//! 2000 --seeds 200`, never flown before): 2 392 → 2 395 of 2 400 (3 channels gained, none
//! lost), contacts 2 → 1 (that one gone); median guard periods per channel run 66.5 → 56.5.
//! Seeds 0–199: 2 398 → 2 397 (boxes 189, at 3.4 × its reference time before, timed out),
//! no contact either way; median guard periods per run in channels, wall gaps and serpentines
//! 62 → 53, 52 → 43 and 45.5 → 37.5. Multipoint and navfn, seeds 0–199: 2 375 → 2 378 and
//! 2 230 → 2 235 of 2 400, contacts 1 → 1 and 0 → 0 (the same run). The flat-fish with its
//! recipe, seeds 0–169: 1 832 → 1 828 of 2 040 (10 gained, 14 lost, chance's share: boxes
//! and clutter at `--trial 1`, 201 → 204 of 340), contacts 1 → 1 (the same run).
//!
//! **Extent.** Each track keeps the largest radius of its compact sightings
//! ([`Tracks::extent`]), which the guard uses for a mover (`crate::guidance::guard`).
//!
//! **Capacity.** One track per sensed obstacle: [`MAX_TRACKS`] = the obstacle table's size.
//! Tracks whose obstacle has left the table (aged out by `World::expire`, evicted, removed)
//! are dropped before a new one is opened, so the track table cannot fill while the world has
//! room; if it ever did, the obstacle is kept without a velocity.
//!
//! Features below the confidence floor are dropped (one beam of speckle or a false target
//! cannot be told from a small object; see the sonar module), but for the glimpses and faint
//! pairs above. When the table is full, the sensed
//! obstacle farthest from the vehicle is evicted if the newcomer is nearer
//! ([`World::upsert_obstacle_or_evict`]); otherwise the newcomer is dropped.

use heapless::Vec;

use super::faint::FaintPairs;
use crate::math::{min, Vec2};
use crate::sonar::Feature;
use crate::world::{Obstacle, Origin, World, MAX_OBJECT_SPEED, MAX_OBSTACLES};

/// First id given to sonar-derived obstacles; ids from the host (charts, contacts) should stay
/// below it.
pub const SONAR_ID_BASE: u16 = 0xC000;

/// Capacity of the track table: one per obstacle table entry.
pub const MAX_TRACKS: usize = MAX_OBSTACLES;

/// A sighting confirms a track's velocity when it lands within `gate_m` plus this fraction of
/// the predicted motion of where the velocity put it.
const STEADY_FRACTION: f32 = 0.25;

/// Below this speed, m/s, a track's velocity is used only once a sighting has landed where it
/// predicted (`Track::steady` ≥ 1): a still rock's fits wander at such speeds (module notes).
const SURE_MPS: f32 = 0.5;

/// Sightings in a row that landed where its velocity put it, after which a track stays a
/// mover when the map's structure runs on from a sighting of it (module notes, "Structure does
/// not move").
const BORNE_OUT: u8 = 2;

/// A sonar track's speed within this of this vehicle's speed along the track's course, m/s,
/// is a track that only keeps pace with the vehicle ([`paces`]).
const PACE_MPS: f32 = 0.12;

/// Whether a sonar track moving at `v` only keeps pace with this vehicle moving at `own`: its
/// speed is within [`PACE_MPS`] of the vehicle's speed along its course. That is how the
/// nearest stretch of a long wall "moves" as the vehicle runs along it: its echoes are strong
/// only abeam, where the beams meet the wall square on, so each sweep fits a fragment a little
/// farther on, and at the rate of the vehicle's own progress along the wall. Such a fragment
/// rated as a mover hid its echoes from the map (`crate::sonar::wakes`) while it slid ahead of
/// the vehicle, so the wall it slid along was never believed there, and the flat-fish met
/// the corner of a channel's bend that only those echoes had shown (channel worlds 111, 185
/// and 198 of `hil bench --models flatfish`: fragments "moving" at 0.58–0.70 m/s, within
/// 0.1 m/s of the vehicle's speed along them). So a slow-turning craft has such a track's
/// echoes painted when it lies against other believed structure (`periodic::hides_wake`). A
/// real mover may keep pace too — one following the vehicle, or crossing at its speed times
/// the cosine of the angle between the courses — but in open water it stands alone: painted
/// there as well, a 0.36 m/s mover following the flat-fish became structure to the tracker in
/// its own wake, and ran into the flat-fish when it stopped (crossing 236 at `--trial 1`).
pub fn paces(v: Vec2, own: Vec2) -> bool {
    let speed = v.norm();
    speed > 0.0 && (own.dot(v) / speed - speed).abs() <= PACE_MPS
}

/// From this speed, m/s, a slow velocity not yet borne out is [`Tracks::tentative`]: the
/// default `min_speed_mps`, below which a track is taken for still.
const TENTATIVE_MPS: f32 = 0.3;

/// From this speed, m/s, rather than [`TENTATIVE_MPS`], the velocity of a track once a mover
/// coming on ([`Track::borne`]) is [`Tracks::tentative`] when a miss has made it still.
const BORNE_MPS: f32 = 0.2;

/// How many times its size (at least 1 m) a track must have drifted from its first sighting
/// for its slow velocity to be [`Tracks::tentative`] whether borne out or not.
const FAR_SIZES: f32 = 3.0;

/// Speed change allowed to a track whose motion is known, between two sightings, m/s: it
/// widens the gate of a rated track by this much per second since its last update.
const MANOEUVRE_MPS: f32 = 0.1;

/// A track none of whose sightings was larger than this, decimetres, is not rated by a second
/// look within `revisit_ms` (module notes, "Hasty looks"): another VideoRay's fits are 0.1–0.3
/// m; rocks', boxes' and the crossing movers' are larger. Not a track of structure's fragments
/// (`Track::largest_dm` = 0: none of its sightings counts), which is never given a velocity and
/// whose wide unrated gate after such a look cost channel worlds successes.
const HASTY_DM: u8 = 5;

/// A track none of whose sightings was larger than this, decimetres, may take a glimpse as its
/// second look (module notes, "Glimpses"): a target narrow enough to be on one beam of a sweep
/// (another VideoRay's first fit was 0.77 m). A rock or a box is on several, and a glimpse
/// near one seen once is more likely speckle or another object than its motion.
const GLIMPSED_DM: u8 = 10;

/// Radius of a mover opened by a faint pair, m: a VideoRay's hull, about what one beam of it
/// fits.
const FAINT_RADIUS_M: f32 = 0.3;

/// Longest time a track is extrapolated over, s (beyond it the gate stops growing).
const MAX_GAP_S: f32 = 10.0;

/// Longest gap over which a track seen once still gates a sighting, s: two sweeps, so a
/// target missed on one sweep (speckle, too few beams at range, a turn of the vehicle) is
/// still the same target when it is seen again, and gets its velocity then. With one sweep
/// a crossing target missed once started a new, still track 7 s before it reached the
/// vehicle (a generated crossing world, own sonar).
const UNRATED_GAP_S: f32 = 2.0 * MAX_GAP_S;

/// Association and tracking settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackConfig {
    /// Features below this confidence are dropped. 0 ..= 1.
    pub min_confidence: f32,
    /// Extra distance beyond the larger of the two radii within which a feature is the same
    /// obstacle, m.
    pub gate_m: f32,
    /// The gate also grows by this speed × the time since the track's last update, m/s ...
    pub gate_speed_mps: f32,
    /// ... once this long has passed since it, ms (about half a sonar sweep).
    pub revisit_ms: u64,
    /// α of the alpha–beta filter, 0 ..= 1.
    pub alpha: f32,
    /// β of the alpha–beta filter, 0 ..= 2.
    pub beta: f32,
    /// Updates closer together than this do not change the velocity, ms.
    pub min_update_ms: u64,
    /// Updates a track needs before its velocity is used.
    pub min_hits: u16,
    /// ... of which this many, after the velocity was set, must land where it predicted
    /// (within `gate_m` + a quarter of the predicted motion). 0: the two-point estimate is used
    /// at once.
    pub min_steady: u16,
    /// Speeds below this are reported as zero, m/s.
    pub min_speed_mps: f32,
    /// Speeds are capped here, m/s (≤ `MAX_OBJECT_SPEED`).
    pub max_speed_mps: f32,
    /// A feature longer than this (the half-length of an elongated fit, or a circle's radius,
    /// m) is structure — a wall, a pier — and is never given a velocity, nor counts towards a
    /// mover's extent.
    pub max_mover_half_m: f32,
}

impl Default for TrackConfig {
    fn default() -> Self {
        TrackConfig {
            min_confidence: 0.15,
            gate_m: 1.0,
            gate_speed_mps: 1.0,
            revisit_ms: 4000,
            alpha: 1.0,
            beta: 1.0 / 3.0,
            min_update_ms: 500,
            min_hits: 2,
            min_steady: 0,
            min_speed_mps: 0.3,
            max_speed_mps: 3.0,
            max_mover_half_m: 3.0,
        }
    }
}

/// What became of one feature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Admission {
    /// Updated the obstacle with this id.
    Updated(u16),
    /// Added as a new obstacle with this id.
    Added(u16),
    /// Dropped: confidence below the floor.
    LowConfidence,
    /// Dropped: its shape or repulsion was refused.
    Invalid,
    /// Dropped: the table is full of nearer obstacles.
    TableFull,
}

/// One sensed obstacle's filter state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Track {
    /// The obstacle's id in the world table.
    pub id: u16,
    /// Filtered centre at `time_ms`, m.
    pub center: Vec2,
    /// Estimated velocity, m/s.
    pub velocity: Vec2,
    /// Time of the last update, ms.
    pub time_ms: u64,
    /// Updates so far (the first sighting is 1), saturating (one byte: the table does not
    /// grow).
    pub hits: u8,
    /// Centre at the first sighting, m.
    pub first: Vec2,
    /// Consecutive sightings since the velocity was set that fell where it predicted.
    pub steady: u8,
    /// Its velocity has been estimated (two sightings far enough apart in time).
    pub rated: bool,
    /// The largest radius a sighting of it has had, decimetres rounded up (saturating at
    /// 25.5 m; one byte, so the table does not grow): see [`Tracks::extent`].
    pub largest_dm: u8,
    /// Opened by a faint pair ([`super::faint`]): its later faint sightings are its next looks.
    pub faint: bool,
    /// It was once a mover borne out and coming on (`Track::closing`), which the guard keeps
    /// meeting when a wandering fit makes it still ([`Tracks::tentative`]).
    pub borne: bool,
}

impl Track {
    fn predict(&self, time_ms: u64) -> (Vec2, f32) {
        let dt = min(
            time_ms.saturating_sub(self.time_ms) as f32 * 1e-3,
            MAX_GAP_S,
        );
        (self.center + self.velocity * dt, dt)
    }

    /// Time from the last update to `time_ms` an unrated track may have moved over, s (at most
    /// [`UNRATED_GAP_S`]).
    fn unrated_gap_s(&self, time_ms: u64) -> f32 {
        min(
            time_ms.saturating_sub(self.time_ms) as f32 * 1e-3,
            UNRATED_GAP_S,
        )
    }

    /// The alpha–beta update with measurement `z` at `time_ms` (see the module notes).
    fn update(&mut self, cfg: &TrackConfig, z: Vec2, time_ms: u64) {
        let (predicted, dt) = self.predict(time_ms);
        // A track seen once has no motion to extrapolate: its first velocity is the two
        // centres over the whole gap it was gated over.
        let dt = if self.rated {
            dt
        } else {
            self.unrated_gap_s(time_ms)
        };
        let r = z - predicted;
        self.center = predicted + r * cfg.alpha;
        // Two looks in one pass of the head say nothing of a small target's motion: it stays
        // seen once, where it was seen last (module notes, "Hasty looks").
        let hasty = time_ms < self.time_ms.saturating_add(cfg.revisit_ms);
        if !self.rated && hasty && (1..=HASTY_DM).contains(&self.largest_dm) {
            self.time_ms = self.time_ms.max(time_ms);
            return;
        }
        if time_ms >= self.time_ms.saturating_add(cfg.min_update_ms) && dt > 0.0 {
            let cap = min(cfg.max_speed_mps, MAX_OBJECT_SPEED);
            // The second sighting sets the velocity from the two centres (a sweep apart), the
            // usual two-point start of an alpha–beta filter; later ones correct it by β.
            let gain = if self.hits == 1 { 1.0 } else { cfg.beta };
            if self.hits > 1 {
                let tol = cfg.gate_m + STEADY_FRACTION * self.velocity.norm() * dt;
                self.steady = if r.norm() <= tol {
                    self.steady.saturating_add(1)
                } else {
                    0
                };
            }
            // A fit's centre is a metre or so off (another face of the target), so two fits
            // a second apart say nothing of its speed: the correction is taken over at least
            // half a sweep (`revisit_ms`), whatever the gap.
            let span = crate::math::max(dt, cfg.revisit_ms as f32 * 1e-3);
            self.velocity = (self.velocity + r * (gain / span)).bounded(cap);
            self.time_ms = time_ms;
            self.rated = true;
        } else {
            self.time_ms = self.time_ms.max(time_ms);
        }
        self.hits = self.hits.saturating_add(1);
    }

    /// Whether it is a mover coming towards the vehicle at `vehicle`, borne out [`BORNE_OUT`]
    /// times in a row: what structure running on from it does not make still (module notes,
    /// "Structure does not move").
    fn closing(&self, vehicle: Vec2) -> bool {
        self.steady >= BORNE_OUT
            && (vehicle - self.center)
                .normalized(1e-3)
                .is_some_and(|u| u.dot(self.velocity) >= TENTATIVE_MPS)
    }

    /// The largest radius its sightings have had, m ([`Tracks::extent`]).
    fn extent_m(&self) -> f32 {
        f32::from(self.largest_dm) * 0.1
    }

    /// The velocity the planner is given, for a target of radius `radius`.
    fn reported_velocity(&self, cfg: &TrackConfig, radius: f32) -> Vec2 {
        let speed2 = self.velocity.norm2();
        // A slow velocity must first have predicted a sighting (module notes).
        let steady = if speed2 < SURE_MPS * SURE_MPS {
            cfg.min_steady.max(1)
        } else {
            cfg.min_steady
        };
        let confirmed = u16::from(self.hits) >= cfg.min_hits && u16::from(self.steady) >= steady;
        let travelled = (self.center - self.first).norm() >= crate::math::max(radius, 1.0);
        if confirmed && travelled && speed2 >= cfg.min_speed_mps * cfg.min_speed_mps {
            self.velocity
        } else {
            Vec2::ZERO
        }
    }
}

/// Whether `center` lies within `within` of an obstacle believed: one beam there is that
/// obstacle's face.
#[inline(never)]
fn on_believed(world: &World, center: Vec2, within: f32) -> bool {
    world
        .obstacles()
        .iter()
        .any(|o| o.shape.signed_distance(center) <= within)
}

/// A sonar obstacle: `shape` with repulsion `a_plus`, seen at `time_ms`, moving at `velocity`.
/// (This and the other `#[inline(never)]` helpers here have several callers: inlined, they cost
/// the NUCLEO image flash it does not have: 1 640 bytes of its 128 KiB are left.)
#[inline(never)]
fn sensed(
    id: u16,
    shape: crate::field::Shape,
    a_plus: f32,
    time_ms: u64,
    velocity: Vec2,
) -> Result<Obstacle, crate::world::ObjectError> {
    Obstacle::new(id, shape, a_plus, Origin::Sonar, time_ms).and_then(|o| o.moving(velocity))
}

/// `r` in decimetres, rounded up, within one byte (`as` saturates: NaN and negatives give 0,
/// 25.5 m and more 255).
fn decimetres(r: f32) -> u8 {
    libm::ceilf(r * 10.0) as u8
}

/// Track table and id allocation for sonar obstacles.
#[derive(Clone, Debug, PartialEq)]
pub struct Tracks {
    next_id: u16,
    tracks: Vec<Track, MAX_TRACKS>,
    /// A glimpse in two tracks' gates (centre, time), until a later sighting settles which.
    held: Option<(Vec2, u64)>,
    /// Faint sightings waiting for a second (module notes, "Faint pairs").
    faint: FaintPairs,
    /// This vehicle's velocity over ground, m/s (`Tracks::own_velocity`).
    own_velocity: Vec2,
}

/// Which track a glimpse is the second look at.
enum Glimpsed {
    None,
    One(usize),
    /// Two or more: held ([`Tracks::settle_held`]).
    Many,
}

impl Default for Tracks {
    fn default() -> Self {
        Tracks {
            next_id: SONAR_ID_BASE,
            tracks: Vec::new(),
            held: None,
            faint: FaintPairs::new(),
            own_velocity: Vec2::ZERO,
        }
    }
}

impl Tracks {
    /// The tracks.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }

    /// The largest radius obstacle `id`'s sightings have had, m, if it is tracked.
    ///
    /// A scanning sonar sees a mover's near face at a different place each sweep, and a
    /// target crossing against the sweep shows it fewer beams each time: the circle fitted to
    /// one sweep's echoes shrank from 1.6 m to 0.3 m round a 1.9 m target in a generated
    /// crossing world, and a guard that took the last fit let it run into the vehicle. Its
    /// largest sighting is the better bound on its extent ([`crate::guidance::guard`]).
    pub fn extent(&self, id: u16) -> Option<f32> {
        self.tracks.iter().find(|t| t.id == id).map(Track::extent_m)
    }

    /// The velocity track `id`'s sightings suggest but that it is not yet given, m/s: a slow
    /// one ([`TENTATIVE_MPS`] up to [`SURE_MPS`]) that no sighting has borne out yet, on a
    /// track that has moved farther than its size since it was first seen (module notes,
    /// "Slow movers"): the guard meets it on that velocity too (`crate::guidance::guard`).
    /// For a track once a mover coming on ([`Track::borne`]), from [`BORNE_MPS`] ("Once a
    /// mover"). Structure never has one.
    ///
    /// Also, from [`BORNE_MPS`] and borne out or not, the velocity of a track that has drifted
    /// [`FAR_SIZES`] times its size (at least 1 m) from its first sighting, if it stands
    /// `alone` (asked last): no rock's fits wander that far, but a wall's fragment slides along
    /// the wall as the vehicle passes ("Drifting").
    pub fn tentative(&self, id: u16, alone: impl FnOnce() -> bool) -> Option<Vec2> {
        let t = self.tracks.iter().find(|t| t.id == id)?;
        let speed2 = t.velocity.norm2();
        let slow = |floor: f32| (floor * floor..SURE_MPS * SURE_MPS).contains(&speed2);
        let size = crate::math::max(t.extent_m(), 1.0);
        let moved = (t.center - t.first).norm();
        let floor = if t.borne { BORNE_MPS } else { TENTATIVE_MPS };
        let unborne = t.steady == 0 && moved >= size && slow(floor);
        let unused = t.steady == 0 || speed2 < TENTATIVE_MPS * TENTATIVE_MPS;
        let drifting = || moved >= FAR_SIZES * size && slow(BORNE_MPS) && unused && alone();
        (t.rated && t.largest_dm > 0 && (unborne || drifting())).then_some(t.velocity)
    }

    /// Whether obstacle `id` is a sonar track a sighting of which was sized as a mover: not
    /// longer than `TrackConfig::max_mover_half_m`, nor a fragment the map's structure runs
    /// on through.
    pub fn mover_sized(&self, id: u16) -> bool {
        self.tracks.iter().any(|t| t.id == id && t.largest_dm > 0)
    }

    /// Whether obstacle `id` is a sonar track of another vessel under way: no sighting of it
    /// larger than another VideoRay's fits ([`HASTY_DM`]), and its velocity borne out by a
    /// sighting where it predicted (`steady`; the simulated sonar's spurious echoes pair into
    /// phantom movers of that size, which none bears out). Such a vessel manoeuvres, and its
    /// own guard turns and stops it when it meets this one (`crate::guidance::guard`, "Close
    /// quarters").
    pub fn vessel(&self, id: u16) -> bool {
        (self.tracks.iter())
            .any(|t| t.id == id && t.steady > 0 && (1..=HASTY_DM).contains(&t.largest_dm))
    }

    /// Whether obstacle `id` is a sonar track whose velocity a sighting has borne out.
    pub fn borne_out(&self, id: u16) -> bool {
        self.tracks.iter().any(|t| t.id == id && t.steady > 0)
    }

    /// Whether obstacle `id` is a sonar track seen more than once.
    pub fn seen_again(&self, id: u16) -> bool {
        self.tracks.iter().any(|t| t.id == id && t.hits >= 2)
    }

    /// Whether obstacle `id` is a sonar track seen only once so far (no velocity can have been
    /// estimated for it: it may be still, or a mover seen once).
    pub fn unrated(&self, id: u16) -> bool {
        self.tracks.iter().any(|t| t.id == id && !t.rated)
    }

    /// A track seen once that took a sighting metres off as its second (a jump, hence a
    /// velocity), and whose first place `f` now shows occupied in the same sweep, was handed
    /// over: the jump was another object (a mover passing a rock the sweep had not yet come
    /// back to). It forgets the jump's velocity and stays, seen once, where it jumped to — or,
    /// when another track seen once owns the jump ([`Tracks::own_track_of_jump`]), goes back
    /// to its first place; `f` then finds the object that stayed (module notes, "Hand-overs").
    fn hand_back(&mut self, cfg: &TrackConfig, world: &mut World, f: &Feature, vehicle: Vec2) {
        let Some(k) = self.tracks.iter().position(|t| {
            let reach = crate::math::max(t.extent_m(), f.radius) + cfg.gate_m;
            let from_first = (f.center - t.first).norm();
            t.rated
                && t.hits == 2
                && f.time_ms < t.time_ms.saturating_add(2 * cfg.revisit_ms)
                && (t.center - t.first).norm() > reach
                && from_first <= reach
                && from_first < (f.center - t.center).norm()
        }) else {
            return;
        };
        let taken = self.own_track_of_jump(cfg, world, k, vehicle);
        let Some(t) = self.tracks.get_mut(k) else {
            return;
        };
        t.velocity = Vec2::ZERO;
        t.rated = false;
        t.hits = 1;
        t.steady = 0;
        if taken {
            // The jump was that track's: this one is back where it was first seen, and `f`
            // (which lands there) moves its obstacle back as its second look.
            t.center = t.first;
        } else {
            t.first = t.center;
        }
        let id = t.id;
        if let Some(o) = world.obstacles().iter().find(|o| o.id == id) {
            if let Ok(o) = o.moving(Vec2::ZERO) {
                let _ = world.upsert_obstacle_or_evict(o, vehicle);
            }
        }
    }

    /// A track rated on a jump this pass of the head, a sweep or so after its first sighting
    /// ([`MAX_GAP_S`]), when `f`, which no track gates, lands nearer its first place than the
    /// jump did and within its unrated gate from there: the jump was another object seen first
    /// (a rock the mover's track reached for), and `f` is the mover. The track goes back to
    /// its first sighting, for `f` to be its second look (its index is returned), and the
    /// jump opens a track of its own, seen once (module notes, "The nearer look").
    fn nearer_look(
        &mut self,
        cfg: &TrackConfig,
        a_plus: f32,
        world: &mut World,
        f: &Feature,
        vehicle: Vec2,
    ) -> Option<usize> {
        // How long before the jump the first sighting was: the two-point start set the
        // velocity to the jump over that gap, and moved the centre α of the jump.
        let gap_s = |t: &Track| {
            let moved = cfg.alpha * t.velocity.norm();
            min((t.center - t.first).norm() / moved.max(1e-3), UNRATED_GAP_S)
        };
        let k = self.tracks.iter().position(|t| {
            let jump = (t.center - t.first).norm();
            let from_first = (f.center - t.first).norm();
            let gap = gap_s(t);
            let since = gap + f.time_ms.saturating_sub(t.time_ms) as f32 * 1e-3;
            let gate = crate::math::max(t.extent_m(), f.radius)
                + cfg.gate_m
                + cfg.gate_speed_mps * min(since, UNRATED_GAP_S);
            t.rated
                && t.hits == 2
                && t.largest_dm > 0
                && gap <= MAX_GAP_S
                && f.time_ms < t.time_ms.saturating_add(cfg.revisit_ms)
                && from_first < jump
                && from_first <= gate
        })?;
        let t = self.tracks.get_mut(k)?;
        let (id, jump, jump_ms) = (t.id, t.center, t.time_ms);
        let gap_ms = (gap_s(t) * 1000.0) as u64;
        *t = Track {
            center: t.first,
            velocity: Vec2::ZERO,
            time_ms: jump_ms.saturating_sub(gap_ms),
            hits: 1,
            steady: 0,
            rated: false,
            ..*t
        };
        let back = *t;
        let shape = world.obstacles().iter().find(|o| o.id == id)?.shape;
        if let Ok(o) = sensed(self.next_id, shape, a_plus, jump_ms, Vec2::ZERO) {
            let opened = Track {
                id: self.next_id,
                center: jump,
                first: jump,
                time_ms: jump_ms,
                largest_dm: decimetres(shape.bounding_radius()),
                faint: false,
                borne: false,
                ..back
            };
            let _ = self.open(world, o, opened, vehicle);
        }
        self.tracks.iter().position(|t| t.id == id)
    }

    /// The jump of track `k` (its second sighting) as the second look at another compact
    /// track seen once whose unrated gate holds it (the nearest if several): the mover seen a
    /// sweep before, which the jump's object is. That track takes it, and its velocity;
    /// `false` if there is none (module notes, "Hand-overs").
    fn own_track_of_jump(
        &mut self,
        cfg: &TrackConfig,
        world: &mut World,
        k: usize,
        vehicle: Vec2,
    ) -> bool {
        let Some(t) = self.tracks.get(k).copied() else {
            return false;
        };
        let gated = |u: &Track| {
            let gate = u.extent_m() + cfg.gate_m + cfg.gate_speed_mps * u.unrated_gap_s(t.time_ms);
            !u.rated
                && u.largest_dm > 0
                && t.time_ms >= u.time_ms.saturating_add(cfg.revisit_ms)
                && (u.center - t.center).norm() <= gate
        };
        let nearest = self
            .tracks
            .iter()
            .enumerate()
            .filter(|&(i, u)| i != k && gated(u))
            .min_by(|(_, a), (_, b)| {
                let d = |u: &Track| (u.center - t.center).norm2();
                d(a).total_cmp(&d(b))
            })
            .map(|(i, _)| i);
        nearest.is_some_and(|i| {
            let shape = world
                .obstacles()
                .iter()
                .find(|o| o.id == t.id)
                .map(|o| o.shape);
            let jump = (t.center, t.time_ms, shape);
            self.take_second_look(cfg, world, i, jump, vehicle) != Admission::LowConfidence
        })
    }

    /// A glimpse `f` (one beam, confidence 0: [`crate::sonar::GLIMPSE_INTENSITY`]) as the
    /// second look at the one compact track seen once, a sweep or more ago, whose gate it
    /// falls in — if it lies on nothing else believed (a rock's edge on one beam is that rock).
    /// In two tracks' gates it is held until the sweep has looked at them again; in none it
    /// goes on as a faint sighting, which opens a track only as one of a pair (module notes,
    /// "Glimpses" and "Faint pairs").
    fn glimpse(
        &mut self,
        cfg: &TrackConfig,
        a_plus: f32,
        world: &mut World,
        f: &Feature,
        vehicle: Vec2,
    ) -> Admission {
        if f.runs_on {
            return Admission::LowConfidence;
        }
        match self.glimpsed(cfg, world, f.center, f.time_ms) {
            Glimpsed::One(i) => {
                self.take_second_look(cfg, world, i, (f.center, f.time_ms, None), vehicle)
            }
            Glimpsed::Many => {
                self.held = Some((f.center, f.time_ms));
                Admission::LowConfidence
            }
            Glimpsed::None => self.faint_pair(cfg, a_plus, world, f, vehicle),
        }
    }

    /// Removes the movers faint pairs opened that nothing has borne out for
    /// [`super::faint::PAIR_MAX_S`] (a sweep or two) by `now_ms`: a spurious pair's phantom,
    /// left the 30 s of a sensed obstacle, held a VideoRay "inside" it where it had last been
    /// while a crossing mover ran into the vehicle (crossing 337).
    fn lapse(&mut self, world: &mut World, now_ms: u64) {
        let life_ms = (super::faint::PAIR_MAX_S * 1000.0) as u64;
        let stale = |t: &Track| t.faint && now_ms > t.time_ms.saturating_add(life_ms);
        for t in self.tracks.iter().filter(|t| stale(t)) {
            world.remove_obstacle(t.id);
        }
        self.tracks.retain(|t| !stale(t));
    }

    /// This vehicle's velocity over ground, for judging faint pairs ([`Tracks::admit`]; with
    /// a NaN, none forms).
    pub fn own_velocity(&mut self, v: Vec2) {
        self.own_velocity = v;
    }

    /// A one-beam sighting `f` that is no track's (module notes, "Faint pairs"): with an
    /// earlier one a new mover on a collision course; else kept for a later one to pair with.
    fn faint_pair(
        &mut self,
        cfg: &TrackConfig,
        a_plus: f32,
        world: &mut World,
        f: &Feature,
        vehicle: Vec2,
    ) -> Admission {
        if f.runs_on || on_believed(world, f.center, crate::sonar::FAINT_ALONE_M) {
            return Admission::LowConfidence;
        }
        let Some(pair) = self
            .faint
            .sighting(f.center, f.time_ms, vehicle, self.own_velocity)
        else {
            return Admission::LowConfidence;
        };
        let cap = min(cfg.max_speed_mps, MAX_OBJECT_SPEED);
        let track = Track {
            id: self.next_id,
            center: f.center,
            velocity: pair.velocity.bounded(cap),
            time_ms: f.time_ms,
            hits: 2,
            first: pair.first,
            steady: 0,
            rated: true,
            largest_dm: decimetres(FAINT_RADIUS_M),
            faint: true,
            borne: false,
        };
        let Ok(shape) = crate::field::Shape::circle(f.center, FAINT_RADIUS_M) else {
            return Admission::Invalid;
        };
        let velocity = track.reported_velocity(cfg, FAINT_RADIUS_M);
        match sensed(track.id, shape, a_plus, f.time_ms, velocity) {
            Ok(o) => self.open(world, o, track, vehicle),
            Err(_) => Admission::Invalid,
        }
    }

    /// The track a glimpse at `center`, `time_ms` is the second look at, if one.
    fn glimpsed(&self, cfg: &TrackConfig, world: &World, center: Vec2, time_ms: u64) -> Glimpsed {
        let gated = |t: &&Track| {
            let gate = t.extent_m() + cfg.gate_m + cfg.gate_speed_mps * t.unrated_gap_s(time_ms);
            !t.rated
                && (1..=GLIMPSED_DM).contains(&t.largest_dm)
                && time_ms >= t.time_ms.saturating_add(cfg.revisit_ms)
                && (t.center - center).norm() <= gate
        };
        let mut candidates = self.tracks.iter().enumerate().filter(|(_, t)| gated(t));
        let (first, second) = (candidates.next(), candidates.next());
        // One beam says little of what it saw: on something believed it is that thing's face.
        match (first, second) {
            (None, _) => Glimpsed::None,
            _ if on_believed(world, center, cfg.gate_m) => Glimpsed::None,
            (Some((i, _)), None) => Glimpsed::One(i),
            (Some(_), Some(_)) => Glimpsed::Many,
        }
    }

    /// Track `i` takes the sighting at (`center`, `time_ms`) as its second look: a glimpse
    /// (its shape unknown: the track's is kept), or another track's jump (`shape`).
    #[inline(never)]
    fn take_second_look(
        &mut self,
        cfg: &TrackConfig,
        world: &mut World,
        i: usize,
        (center, time_ms, shape): (Vec2, u64, Option<crate::field::Shape>),
        vehicle: Vec2,
    ) -> Admission {
        let Some(t) = self.tracks.get_mut(i) else {
            return Admission::LowConfidence;
        };
        let Some(o) = world.obstacles().iter().find(|o| o.id == t.id).copied() else {
            return Admission::LowConfidence;
        };
        t.update(cfg, center, time_ms);
        if let Some(s) = shape {
            t.largest_dm = t.largest_dm.max(decimetres(s.bounding_radius()));
        }
        let shape = shape.unwrap_or(o.shape);
        let radius = shape.bounding_radius();
        let velocity = t.reported_velocity(cfg, radius);
        let at = shape.translated(t.center - shape.center());
        let moved = sensed(t.id, at, o.a_plus(), time_ms, velocity);
        match moved.map(|m| world.upsert_obstacle_or_evict(m, vehicle)) {
            Ok(Ok(_)) => Admission::Updated(t.id),
            Ok(Err(_)) => Admission::TableFull,
            Err(_) => Admission::Invalid,
        }
    }

    /// The held glimpse, once a sighting at `now_ms` may have settled which track it is: a
    /// candidate seen again where it was is rated, or no longer a sweep behind the glimpse.
    /// Held no longer than `revisit_ms` (about half a sweep).
    fn settle_held(&mut self, cfg: &TrackConfig, world: &mut World, now_ms: u64, vehicle: Vec2) {
        let Some((center, time_ms)) = self.held else {
            return;
        };
        if now_ms > time_ms.saturating_add(cfg.revisit_ms) {
            self.held = None;
            return;
        }
        match self.glimpsed(cfg, world, center, time_ms) {
            Glimpsed::Many => {}
            Glimpsed::None => self.held = None,
            Glimpsed::One(i) => {
                self.held = None;
                let _ = self.take_second_look(cfg, world, i, (center, time_ms, None), vehicle);
            }
        }
    }

    /// Puts `f` into `world` with repulsiveness `a_plus` (the planner's A_s⁺), seen from the
    /// vehicle at `vehicle`.
    pub fn admit(
        &mut self,
        cfg: &TrackConfig,
        a_plus: f32,
        world: &mut World,
        f: &Feature,
        vehicle: Vec2,
    ) -> Admission {
        self.lapse(world, f.time_ms);
        // NaN confidence fails the comparison and is dropped too.
        let confident = f.confidence >= cfg.min_confidence;
        if !confident && !f.faint {
            return if f.beams == 1 {
                self.glimpse(cfg, a_plus, world, f, vehicle)
            } else {
                Admission::LowConfidence
            };
        }
        let Ok(shape) = f.to_shape() else {
            return Admission::Invalid;
        };
        // A long echo (a bar, or a circle wider than a vessel), or one the map's structure
        // runs on from, is a wall seen from a new place, not a wall on the move — but a track
        // borne out twice in a row and coming on keeps its velocity through the cells it left
        // behind (module notes, "Structure does not move").
        let long = match f.kind {
            crate::sonar::FeatureKind::Rectangle { half, .. } => {
                crate::math::max(half.x, half.y) > cfg.max_mover_half_m
            }
            crate::sonar::FeatureKind::Circle { .. } => f.radius > cfg.max_mover_half_m,
        };
        let structure = f.runs_on || long;
        self.tracks
            .retain(|t| world.obstacles().iter().any(|o| o.id == t.id));
        if !f.faint {
            self.hand_back(cfg, world, f, vehicle);
        }

        // The nearest track whose predicted centre gates the feature.
        let mut best: Option<(usize, f32)> = None;
        for (i, t) in self.tracks.iter().enumerate() {
            let Some(o) = world.obstacles().iter().find(|o| o.id == t.id) else {
                continue;
            };
            // A rated track moves as estimated, give or take a quarter of that motion and a
            // slow manoeuvre: a rock seen twice in one place does not jump to the next echo
            // that appears a few metres off (a mover passing it), and a wall's echoes, which
            // "move" differently each sweep, start new tracks instead of making one a phantom
            // mover. An unrated track may have moved at up to `gate_speed_mps` in any
            // direction, once a sweep has passed (`revisit_ms`).
            let gap = f.time_ms.saturating_sub(t.time_ms) as f32 * 1e-3;
            let dt = min(gap, MAX_GAP_S);
            let revisit = f.time_ms >= t.time_ms.saturating_add(cfg.revisit_ms);
            let (velocity, allowance) = if t.rated {
                let v = t.velocity;
                (v, (STEADY_FRACTION * v.norm() + MANOEUVRE_MPS) * dt)
            } else if revisit {
                (Vec2::ZERO, cfg.gate_speed_mps * t.unrated_gap_s(f.time_ms))
            } else {
                (Vec2::ZERO, 0.0)
            };
            let d = (t.center + velocity * dt - f.center).norm();
            let reach = crate::math::max(o.shape.bounding_radius(), f.radius);
            let gate = reach + cfg.gate_m + allowance;
            if d <= gate && best.is_none_or(|(_, b)| d < b) {
                best = Some((i, d));
            }
        }
        if best.is_none() && !structure && !f.faint {
            best = self
                .nearer_look(cfg, a_plus, world, f, vehicle)
                .map(|i| (i, 0.0));
        }
        if f.faint {
            // Only a mover a faint pair opened takes a faint sighting as its next look.
            return match best.filter(|(i, _)| self.tracks.get(*i).is_some_and(|t| t.faint)) {
                Some((i, _)) => {
                    self.take_second_look(cfg, world, i, (f.center, f.time_ms, None), vehicle)
                }
                None => self.faint_pair(cfg, a_plus, world, f, vehicle),
            };
        }
        let (id, track) = match best.and_then(|(i, _)| self.tracks.get_mut(i)) {
            Some(t) => {
                t.update(cfg, f.center, f.time_ms);
                t.borne |= t.closing(vehicle);
                if !structure {
                    t.largest_dm = t.largest_dm.max(decimetres(f.radius));
                }
                (t.id, Some(*t))
            }
            None => (self.next_id, None),
        };
        let fresh = track.is_none();
        let velocity = match track {
            Some(t) if !long && (!f.runs_on || t.closing(vehicle)) => {
                t.reported_velocity(cfg, f.radius)
            }
            _ => Vec2::ZERO,
        };
        // The track's centre: with the default α = 1, where the sonar saw it last.
        let center = track.map_or(f.center, |t| t.center);
        let o = sensed(
            id,
            shape.translated(center - f.center),
            a_plus,
            f.time_ms,
            velocity,
        );
        let Ok(o) = o else {
            return Admission::Invalid;
        };
        let admitted = if fresh {
            let track = Track {
                id,
                center: f.center,
                velocity: Vec2::ZERO,
                time_ms: f.time_ms,
                hits: 1,
                first: f.center,
                steady: 0,
                rated: false,
                largest_dm: if structure { 0 } else { decimetres(f.radius) },
                faint: false,
                borne: false,
            };
            self.open(world, o, track, vehicle)
        } else {
            match world.upsert_obstacle_or_evict(o, vehicle) {
                Ok(_) => Admission::Updated(id),
                Err(_) => Admission::TableFull,
            }
        };
        self.settle_held(cfg, world, f.time_ms, vehicle);
        admitted
    }

    /// Puts the new obstacle `o` into the table with its `track`, which takes the next id.
    #[inline(never)]
    fn open(&mut self, world: &mut World, o: Obstacle, track: Track, vehicle: Vec2) -> Admission {
        match world.upsert_obstacle_or_evict(o, vehicle) {
            Ok(_) => {
                self.next_id = self.next_id.checked_add(1).unwrap_or(SONAR_ID_BASE);
                // Drop the track of an obstacle this one evicted; then there is room, since
                // every track's obstacle is in the table.
                self.tracks
                    .retain(|t| world.obstacles().iter().any(|o| o.id == t.id));
                let _ = self.tracks.push(track);
                Admission::Added(track.id)
            }
            Err(_) => Admission::TableFull,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sonar::FeatureKind;

    #[test]
    fn a_walls_fragment_keeps_pace_and_a_crossing_mover_does_not() {
        // The vehicle runs at 0.65 m/s, 20° off a wall along +x: the wall's nearest stretch
        // "moves" along it at 0.61 m/s (channel 185's fragments were within 0.1 m/s of it).
        let own = Vec2::from_angle(0.35) * 0.65;
        assert!(paces(Vec2::new(0.61, 0.0), own));
        assert!(paces(Vec2::new(0.55, 0.0), own));
        // Faster or slower than the vehicle's progress along it, across its track or against
        // it: a mover.
        assert!(!paces(Vec2::new(0.9, 0.0), own));
        assert!(!paces(Vec2::new(0.4, 0.0), own));
        assert!(!paces(Vec2::new(0.0, 0.6), own));
        assert!(!paces(Vec2::new(-0.61, 0.0), own));
        assert!(!paces(Vec2::ZERO, own));
    }

    fn feature(x: f32, y: f32, r: f32, confidence: f32) -> Feature {
        Feature {
            center: Vec2::new(x, y),
            radius: r,
            kind: FeatureKind::Circle { radius: r },
            confidence,
            time_ms: 1000,
            beams: 6,
            runs_on: false,
            faint: false,
        }
    }

    #[test]
    fn same_place_updates_new_place_adds() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        let a = t.admit(&cfg, 2.5, &mut w, &feature(10.0, 0.0, 1.0, 0.9), Vec2::ZERO);
        assert_eq!(a, Admission::Added(SONAR_ID_BASE));
        let b = t.admit(&cfg, 2.5, &mut w, &feature(10.4, 0.3, 1.1, 0.9), Vec2::ZERO);
        assert_eq!(b, Admission::Updated(SONAR_ID_BASE));
        let c = t.admit(&cfg, 2.5, &mut w, &feature(20.0, 0.0, 1.0, 0.9), Vec2::ZERO);
        assert_eq!(c, Admission::Added(SONAR_ID_BASE + 1));
        assert_eq!(w.obstacles().len(), 2);
    }

    fn at(mut f: Feature, t_ms: u64) -> Feature {
        f.time_ms = t_ms;
        f
    }

    #[test]
    fn a_moving_feature_gets_its_velocity_and_a_static_one_none() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        let mut rng = crate::math::XorShift32::new(7);
        let mut noise = || (rng.next_u32() as f32 / u32::MAX as f32 - 0.5) * 0.4; // ±0.2 m
                                                                                  // A sweep every 4 s; one target crosses at (0.5, −0.3) m/s, a rock sits still.
        for k in 0..12u64 {
            let s = 4.0 * k as f32;
            let mover = feature(20.0 + 0.5 * s + noise(), 5.0 - 0.3 * s + noise(), 1.5, 0.9);
            let rock = feature(-15.0 + noise(), 8.0 + noise(), 2.0, 0.9);
            for f in [mover, rock] {
                let a = t.admit(&cfg, 2.5, &mut w, &at(f, 4000 * k), Vec2::ZERO);
                assert!(
                    matches!(a, Admission::Added(_) | Admission::Updated(_)),
                    "{a:?}"
                );
            }
        }
        assert_eq!(w.obstacles().len(), 2, "each target stays one obstacle");
        let v = w.obstacles()[0].velocity;
        assert!((v - Vec2::new(0.5, -0.3)).norm() < 0.08, "mover {v:?}");
        assert_eq!(
            w.obstacles()[1].velocity,
            Vec2::ZERO,
            "the rock does not drift"
        );
        // The mover's centre is the filtered one, near the truth at t = 44 s.
        let c = w.obstacles()[0].shape.center();
        assert!((c - Vec2::new(42.0, -8.2)).norm() < 0.5, "{c:?}");
    }

    #[test]
    fn an_unconfirmed_track_reports_no_velocity_and_stale_tracks_go() {
        // Three hits wanted here, so two are unconfirmed (the default, two, is tested below).
        let cfg = TrackConfig {
            min_hits: 3,
            ..TrackConfig::default()
        };
        let mut w = World::new();
        let mut t = Tracks::default();
        t.admit(
            &cfg,
            2.5,
            &mut w,
            &at(feature(10.0, 0.0, 1.0, 0.9), 0),
            Vec2::ZERO,
        );
        // Moved 3 m in 4 s: beyond radius + gate_m, within the speed allowance; one hit more.
        let a = t.admit(
            &cfg,
            2.5,
            &mut w,
            &at(feature(13.0, 0.0, 1.0, 0.9), 4000),
            Vec2::ZERO,
        );
        assert_eq!(a, Admission::Updated(SONAR_ID_BASE));
        assert_eq!(
            w.obstacles()[0].velocity,
            Vec2::ZERO,
            "two hits: not yet confirmed"
        );
        assert_eq!(t.tracks().len(), 1);
        // With the defaults the two-point start sets the velocity and it is reported at once;
        // wanting a steady sighting (`min_steady` 1) holds it back until a third lands where it
        // predicted, and not if the third jumps elsewhere.
        let fly = |cfg: &TrackConfig, xs: &[f32]| {
            let mut w2 = World::new();
            let mut t2 = Tracks::default();
            for (k, &x) in xs.iter().enumerate() {
                let f = at(feature(x, 0.0, 1.0, 0.9), 4000 * k as u64);
                t2.admit(cfg, 2.5, &mut w2, &f, Vec2::ZERO);
            }
            (w2.obstacles()[0].velocity, w2.obstacles().len())
        };
        let d = TrackConfig::default();
        assert!((fly(&d, &[10.0, 13.0]).0 - Vec2::new(0.75, 0.0)).norm() < 1e-4);
        let steady = TrackConfig {
            min_steady: 1,
            ..TrackConfig::default()
        };
        assert_eq!(fly(&steady, &[10.0, 13.0]).0, Vec2::ZERO, "not yet steady");
        assert!((fly(&steady, &[10.0, 13.0, 16.2]).0 - Vec2::new(0.75, 0.0)).norm() < 0.02);
        // A sighting 4 m behind where a rated track predicted (16) is not that track: it
        // starts another (with a wide unrated gate it would have dragged the first back).
        assert_eq!(
            fly(&d, &[10.0, 13.0, 12.0]).1,
            2,
            "a jump back is another object"
        );
        // Not seen for 30 s: the world drops it, and the track goes with it.
        w.expire(40_000, 30_000);
        assert!(w.obstacles().is_empty());
        t.admit(
            &cfg,
            2.5,
            &mut w,
            &at(feature(-20.0, 0.0, 1.0, 0.9), 40_000),
            Vec2::ZERO,
        );
        assert_eq!(t.tracks().len(), 1);
        assert_eq!(t.tracks()[0].id, SONAR_ID_BASE + 1);
    }

    #[test]
    fn a_neighbour_seen_later_in_the_same_sweep_is_not_merged() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // Two rocks 5 m apart, seen 2 s apart in one sweep and again 9 s later.
        for sweep in 0..3u64 {
            let t0 = 9000 * sweep;
            t.admit(
                &cfg,
                2.5,
                &mut w,
                &at(feature(10.0, 0.0, 1.0, 0.9), t0),
                Vec2::ZERO,
            );
            t.admit(
                &cfg,
                2.5,
                &mut w,
                &at(feature(10.0, 5.0, 1.0, 0.9), t0 + 2000),
                Vec2::ZERO,
            );
        }
        assert_eq!(w.obstacles().len(), 2);
        for o in w.obstacles() {
            assert_eq!(o.velocity, Vec2::ZERO);
        }
        let near = |y: f32| {
            w.obstacles()
                .iter()
                .any(|o| (o.shape.center().y - y).abs() < 1e-3)
        };
        assert!(near(0.0) && near(5.0));
    }

    #[test]
    fn a_rock_seen_twice_is_not_taken_over_by_a_neighbour() {
        // Two boxes 8 m apart. The first is seen in two sweeps (rated, still); the second
        // appears in the third sweep: within the 1 m/s × 9 s of an unrated gate, outside the
        // rated one. It becomes an obstacle of its own and the first stays put, still.
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        for k in 0..2u64 {
            let f = at(feature(-5.0, 27.5, 1.9, 0.9), 9000 * k);
            t.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
        }
        let b = at(feature(2.8, 23.0, 1.9, 0.9), 18_000);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &b, Vec2::ZERO),
            Admission::Added(SONAR_ID_BASE + 1)
        );
        let a = w.obstacles()[0];
        assert!((a.shape.center() - Vec2::new(-5.0, 27.5)).norm() < 1e-3);
        assert_eq!(a.velocity, Vec2::ZERO);
    }

    #[test]
    fn the_track_table_never_outgrows_the_world() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // 40 features far apart, walking away: later ones evict none (farther), so the world
        // and the tracks stay at capacity together.
        for i in 0..40u64 {
            let f = feature(10.0 * i as f32, 0.0, 1.0, 0.9);
            t.admit(&cfg, 2.5, &mut w, &at(f, 100 * i), Vec2::ZERO);
            assert!(t.tracks().len() <= w.obstacles().len());
        }
        assert_eq!(w.obstacles().len(), MAX_TRACKS);
        // Nearer ones evict the farthest: tracks follow.
        for i in 0..8u64 {
            let f = feature(-5.0 - 10.0 * i as f32, 50.0, 1.0, 0.9);
            let a = t.admit(
                &cfg,
                2.5,
                &mut w,
                &at(f, 5000 + 100 * i),
                Vec2::new(-40.0, 50.0),
            );
            assert!(matches!(a, Admission::Added(_)), "{a:?}");
            assert_eq!(t.tracks().len(), w.obstacles().len());
        }
    }

    #[test]
    fn weak_or_broken_features_are_dropped() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // Below the floor of two strong beams (one beam, or two faint ones).
        let weak = feature(10.0, 0.0, 1.0, 0.1);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &weak, Vec2::ZERO),
            Admission::LowConfidence
        );
        let nan = feature(10.0, 0.0, 1.0, f32::NAN);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &nan, Vec2::ZERO),
            Admission::LowConfidence
        );
        let broken = feature(f32::INFINITY, 0.0, 1.0, 0.9);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &broken, Vec2::ZERO),
            Admission::Invalid
        );
        assert!(w.obstacles().is_empty());
    }

    fn wall(x: f32, y: f32, half_len: f32, t_ms: u64) -> Feature {
        Feature {
            center: Vec2::new(x, y),
            radius: half_len,
            kind: FeatureKind::Rectangle {
                half: Vec2::new(half_len, 0.5),
                angle: 0.0,
            },
            confidence: 0.9,
            time_ms: t_ms,
            beams: 20,
            runs_on: false,
            faint: false,
        }
    }

    /// A vehicle running along y = 0 at 1 m/s, with a sighting `at(x, t_ms)` abeam of it every
    /// 9 s (one sweep's fit of what runs beside it).
    fn run_along(at: impl Fn(f32, u64) -> Feature) -> (World, Tracks) {
        let (cfg, mut w, mut t) = (TrackConfig::default(), World::new(), Tracks::default());
        for k in 0..6u64 {
            let x = 9.0 * k as f32;
            t.admit(&cfg, 2.5, &mut w, &at(x, 9000 * k), Vec2::new(x, 0.0));
        }
        (w, t)
    }

    #[test]
    fn a_wall_seen_from_new_places_never_moves_and_a_short_box_may() {
        // A vehicle running along a quay: each sweep's fit is centred abeam of it.
        let run_along_marked = |half_len: f32, runs_on: bool| {
            run_along(|x, t_ms| Feature {
                runs_on,
                ..wall(x, 5.0, half_len, t_ms)
            })
        };
        let (w, t) = run_along_marked(6.0, false);
        assert_eq!(w.obstacles().len(), 1, "one track along the quay");
        assert_eq!(w.obstacles()[0].velocity, Vec2::ZERO);
        assert_eq!(t.extent(w.obstacles()[0].id), Some(0.0), "no mover extent");
        // A 2 m box doing the same is a mover.
        let (w, _) = run_along_marked(1.0, false);
        let v = w.obstacles()[0].velocity;
        assert!((v - Vec2::new(1.0, 0.0)).norm() < 0.05, "{v:?}");
        // ... unless the evidence map's wall runs on through each of its sightings: then it is
        // the wall's fragment abeam (a grazing wall returns a short run of echoes).
        let (w, _) = run_along_marked(1.0, true);
        assert_eq!(w.obstacles()[0].velocity, Vec2::ZERO);
    }

    #[test]
    fn a_circle_wider_than_a_vessel_never_moves() {
        // A wall's curved run of echoes fitted as a circle 10 m across, abeam of a vehicle
        // running along it at 1 m/s, sweep after sweep (module notes, "Structure does not
        // move"); a 2 m target doing the same is a mover.
        let circles = |r: f32| {
            run_along(|x, t_ms| Feature {
                time_ms: t_ms,
                ..feature(x, 5.0 + r, r, 0.9)
            })
        };
        let (w, t) = circles(5.0);
        assert_eq!(w.obstacles().len(), 1, "one track along the wall");
        assert_eq!(w.obstacles()[0].velocity, Vec2::ZERO);
        assert_eq!(t.extent(w.obstacles()[0].id), Some(0.0), "no mover extent");
        let (w, _) = circles(1.0);
        let v = w.obstacles()[0].velocity;
        assert!((v - Vec2::new(1.0, 0.0)).norm() < 0.05, "{v:?}");
    }

    #[test]
    fn a_mover_borne_out_and_closing_stays_a_mover_where_structure_runs_on() {
        // A 2 m target closing on a still vehicle at 0.85 m/s, seen every 3.2 s; the map's
        // structure (its own wake) runs on from its last sighting of `n`.
        let fly = |n: u64| {
            let (cfg, mut w, mut t) = (TrackConfig::default(), World::new(), Tracks::default());
            for k in 0..n {
                let f = Feature {
                    runs_on: k + 1 == n,
                    ..feature(0.0, 25.0 - 0.85 * 3.2 * k as f32, 2.0, 0.9)
                };
                t.admit(&cfg, 2.5, &mut w, &at(f, 3200 * k), Vec2::ZERO);
            }
            w.obstacles()[0].velocity
        };
        // Its third and fourth sightings landed where the first two put them: a mover.
        // (The velocity is still converging: corrections are taken over at least `revisit_ms`.)
        let v = fly(4);
        assert!(v.y < -0.6 && v.x.abs() < 0.05, "{v:?}");
        // Only the third has: structure.
        assert_eq!(fly(3), Vec2::ZERO);
        // Going away, it is structure however well borne out.
        let (cfg, mut w, mut t) = (TrackConfig::default(), World::new(), Tracks::default());
        for k in 0..6u64 {
            let f = Feature {
                runs_on: k == 5,
                ..feature(0.0, 10.0 + 0.85 * 3.2 * k as f32, 2.0, 0.9)
            };
            t.admit(&cfg, 2.5, &mut w, &at(f, 3200 * k), Vec2::ZERO);
        }
        assert_eq!(w.obstacles()[0].velocity, Vec2::ZERO);
    }

    #[test]
    fn a_mover_keeps_the_extent_of_its_largest_sighting() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // Fits shrinking as the target crosses against the sweep (as measured: 1.6 → 0.3 m).
        for (k, r) in [1.6f32, 1.2, 0.7, 0.3].into_iter().enumerate() {
            let s = 9.0 * k as f32;
            let f = feature(20.0 + 0.6 * s, 10.0 - 0.5 * s, r, 0.9);
            t.admit(&cfg, 2.5, &mut w, &at(f, 9000 * k as u64), Vec2::ZERO);
        }
        let o = w.obstacles()[0];
        assert!(o.velocity.norm() > 0.5, "a mover: {:?}", o.velocity);
        assert!(
            (o.shape.bounding_radius() - 0.3).abs() < 1e-6,
            "the last fit"
        );
        assert_eq!(t.extent(o.id), Some(1.6));
    }

    #[test]
    fn a_target_missed_on_one_sweep_is_still_the_same_target() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // Seen at 0 s, missed at 9 s, seen again at 18 s 14 m on: 0.78 m/s.
        let v = Vec2::new(0.6, -0.5);
        for k in [0u64, 2] {
            let s = 9.0 * k as f32;
            let f = feature(20.0 + v.x * s, 30.0 + v.y * s, 1.1, 0.9);
            t.admit(&cfg, 2.5, &mut w, &at(f, 9000 * k), Vec2::ZERO);
        }
        assert_eq!(w.obstacles().len(), 1, "one target");
        let got = w.obstacles()[0].velocity;
        assert!(
            (got - v).norm() < 1e-3,
            "its velocity over the gap: {got:?}"
        );
    }

    #[test]
    fn a_second_look_soon_after_hardly_moves_the_velocity() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        // Seen a sweep apart at (−0.7, −0.46) m/s; the vehicle turns and the head meets the
        // target again 1.5 s later, the fit 1.9 m off its predicted centre (another face).
        let v = Vec2::new(-0.7, -0.46);
        for k in [0u64, 1] {
            let s = 9.0 * k as f32;
            let f = feature(20.0 + v.x * s, 30.0 + v.y * s, 1.3, 0.9);
            t.admit(&cfg, 2.5, &mut w, &at(f, 9000 * k), Vec2::ZERO);
        }
        let p = Vec2::new(20.0, 30.0) + v * 10.5 + Vec2::new(0.2, 1.9);
        t.admit(
            &cfg,
            2.5,
            &mut w,
            &at(feature(p.x, p.y, 0.9, 0.9), 10_500),
            Vec2::ZERO,
        );
        assert_eq!(w.obstacles().len(), 1, "one target");
        let got = w.obstacles()[0].velocity;
        // Over 1.5 s the β correction would be 0.42 m/s; over half a sweep (4 s), 0.16.
        assert!((got - v).norm() < 0.2, "{got:?}");
    }

    #[test]
    fn a_slow_velocity_is_used_once_it_has_predicted_a_sighting() {
        let cfg = TrackConfig::default();
        let (mut w, mut t) = (World::new(), Tracks::default());
        let (mut w2, mut t2) = (World::new(), Tracks::default());
        // A sweep every 9 s. A diver at 0.4 m/s; a rock whose fits wander 3.6 m between two
        // faces, as if at 0.4 m/s, then back.
        let v = Vec2::new(0.4, 0.0);
        let rock = [
            Vec2::new(20.0, 5.0),
            Vec2::new(23.6, 5.0),
            Vec2::new(20.2, 5.0),
        ];
        for k in 0..3u64 {
            let s = 9.0 * k as f32;
            let d = Vec2::new(10.0, -10.0) + v * s;
            t.admit(
                &cfg,
                2.5,
                &mut w,
                &at(feature(d.x, d.y, 1.0, 0.9), 9000 * k),
                Vec2::ZERO,
            );
            let r = rock[k as usize];
            t2.admit(
                &cfg,
                2.5,
                &mut w2,
                &at(feature(r.x, r.y, 2.0, 0.9), 9000 * k),
                Vec2::ZERO,
            );
            let (diver, stone) = (w.obstacles()[0].velocity, w2.obstacles()[0].velocity);
            if k < 2 {
                assert_eq!(diver, Vec2::ZERO, "two sightings of a slow target: not yet");
            } else {
                assert!(
                    (diver - v).norm() < 1e-3,
                    "the third confirmed it: {diver:?}"
                );
            }
            assert_eq!(stone, Vec2::ZERO, "the rock never moves");
        }
    }

    #[test]
    fn a_mover_once_coming_on_stays_one_to_the_guard_after_a_miss() {
        // A target at 0.4 m/s seen every 4 s, borne out twice, then a sighting 1.8 m short
        // of where it should be: still to the planner, its velocity β-pulled to 0.25 m/s
        // (under the 0.3 floor of a fresh slow track). Coming on, the guard still meets it;
        // going away, as a wall's fragment keeps pace with a vehicle, it does not — while it
        // stands against other believed structure. Alone, 4.6 m from its first sighting
        // (more than three times its size), it has drifted farther than a rock's fits wander,
        // and the guard meets it either way.
        let cfg = TrackConfig::default();
        for (vehicle, met) in [(Vec2::ZERO, true), (Vec2::new(-40.0, 0.0), false)] {
            let (mut w, mut t) = (World::new(), Tracks::default());
            for k in 0..5u64 {
                let x = -16.0 + 1.6 * k as f32 - if k == 4 { 1.8 } else { 0.0 };
                let f = at(feature(x, 0.0, 1.0, 0.9), 4000 * k);
                t.admit(&cfg, 2.5, &mut w, &f, vehicle);
            }
            let o = w.obstacles()[0];
            assert_eq!(o.velocity, Vec2::ZERO, "a miss: still to the planner");
            let v = t.tentative(o.id, || false);
            assert_eq!(v.is_some(), met, "vehicle at {vehicle:?}: {v:?}");
            let alone = t.tentative(o.id, || true);
            for v in v.iter().chain(alone.iter()) {
                assert!((v.norm() - 0.25).abs() < 1e-3, "{v:?}");
            }
            assert!(alone.is_some(), "drifted, alone: met");
        }
    }

    #[test]
    fn a_rock_whose_fits_wander_never_drifts() {
        // A 1 m rock seen every 4 s for a minute, each fit up to 1.2 m off its centre: its
        // filter may find a slow velocity, but it never gets three sizes from where it was
        // first seen, so alone in open water it is still to the guard too.
        let cfg = TrackConfig::default();
        let (mut w, mut t) = (World::new(), Tracks::default());
        let wander = [(0.0, 0.0), (1.2, 0.0), (0.0, 1.2), (-1.2, 0.0), (0.0, -1.2)];
        for k in 0..15u64 {
            let (dx, dy) = wander[k as usize % wander.len()];
            let f = at(feature(10.0 + dx, 5.0 + dy, 1.0, 0.9), 4000 * k);
            t.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO);
            let o = w.obstacles()[0];
            assert_eq!(t.tentative(o.id, || true), None, "sighting {k}");
        }
    }

    #[test]
    fn a_rock_seen_again_in_the_sweep_a_mover_took_its_track_in_takes_it_back() {
        let cfg = TrackConfig::default();
        let (mut w, mut t) = (World::new(), Tracks::default());
        let admit = |t: &mut Tracks, w: &mut World, x: f32, y: f32, ms: u64| {
            t.admit(&cfg, 2.5, w, &at(feature(x, y, 1.0, 0.9), ms), Vec2::ZERO)
        };
        // A rock seen once; a sweep later a mover, seen for the first time 7 m off it, takes
        // its track (a rock seen once may be a mover) and gets a velocity from the jump...
        assert_eq!(
            admit(&mut t, &mut w, 20.0, 0.0, 0),
            Admission::Added(SONAR_ID_BASE)
        );
        admit(&mut t, &mut w, 24.0, 6.0, 9000);
        assert_ne!(
            w.obstacles()[0].velocity,
            Vec2::ZERO,
            "the jump made a mover"
        );
        // ... until, later in the same sweep, the rock is seen where it was.
        let rock = admit(&mut t, &mut w, 20.2, 0.1, 11000);
        assert_eq!(
            rock,
            Admission::Added(SONAR_ID_BASE + 1),
            "the rock is a track again"
        );
        let mover = w.obstacles().iter().find(|o| o.id == SONAR_ID_BASE);
        assert!(
            mover.is_some_and(|o| o.velocity == Vec2::ZERO && o.shape.center().x == 24.0),
            "the mover is where it was seen, with no velocity yet: {mover:?}"
        );
        assert!(t.unrated(SONAR_ID_BASE), "seen once");
        // A sweep after the jump, the same echo at the first place is not a hand-back.
        let (mut w2, mut t2) = (World::new(), Tracks::default());
        admit(&mut t2, &mut w2, 20.0, 0.0, 0);
        admit(&mut t2, &mut w2, 24.0, 6.0, 9000);
        admit(&mut t2, &mut w2, 20.2, 0.1, 18000);
        assert!(!t2.unrated(SONAR_ID_BASE), "a sweep later the jump stands");
    }

    #[test]
    fn a_handed_back_jump_goes_to_the_mover_seen_a_sweep_before() {
        let cfg = TrackConfig::default();
        let (mut w, mut t) = (World::new(), Tracks::default());
        let admit = |t: &mut Tracks, w: &mut World, x: f32, y: f32, ms: u64| {
            t.admit(&cfg, 2.5, w, &at(feature(x, y, 1.0, 0.9), ms), Vec2::ZERO)
        };
        let (mover, rock) = (SONAR_ID_BASE, SONAR_ID_BASE + 1);
        // A mover seen once at (20, 10), a rock seen once at (20, 0) half a second later.
        assert_eq!(
            admit(&mut t, &mut w, 20.0, 10.0, 0),
            Admission::Added(mover)
        );
        assert_eq!(
            admit(&mut t, &mut w, 20.0, 0.0, 500),
            Admission::Added(rock)
        );
        // A sweep later the mover, 7 m on at (23, 4), is nearer the rock's track, and takes
        // it ...
        assert_eq!(
            admit(&mut t, &mut w, 23.0, 4.0, 9000),
            Admission::Updated(rock)
        );
        // ... until the rock is seen where it was: the jump is the mover's second look (its
        // velocity from (20, 10)), and the rock is a rock seen twice, still.
        assert_eq!(
            admit(&mut t, &mut w, 20.1, 0.1, 9400),
            Admission::Updated(rock)
        );
        let o = |id: u16| w.obstacles().iter().find(|o| o.id == id).copied();
        let m = o(mover).map(|o| (o.shape.center(), o.velocity));
        assert!(
            m.is_some_and(|(c, v)| c == Vec2::new(23.0, 4.0) && v.x > 0.3 && v.y < -0.3),
            "the mover moves on from where it was seen: {m:?}"
        );
        let r = o(rock).map(|o| (o.shape.center(), o.velocity));
        assert!(
            r.is_some_and(|(c, v)| (c - Vec2::new(20.1, 0.1)).norm() < 1e-3 && v == Vec2::ZERO),
            "the rock is still where it is: {r:?}"
        );
        assert_eq!(w.obstacles().len(), 2, "no third object");
    }

    #[test]
    fn a_jump_to_a_rock_gives_way_to_a_nearer_look_in_the_same_pass() {
        // Generated crossing seed 69 (flat-fish, 40 m sonar): a mover seen once at (55.7, 2.5);
        // a sweep later the head passed a rock 6.4 m from there first, which the mover's track
        // took as its second look (a 1.1 m/s "mover" going the wrong way), and the mover
        // itself 0.2 s later, 5 m on, nearer the first place.
        let cfg = TrackConfig::default();
        let fly = |first_ms: u64| {
            let (mut w, mut t) = (World::new(), Tracks::default());
            let mut admit = |x: f32, y: f32, r: f32, ms: u64| {
                t.admit(
                    &cfg,
                    2.5,
                    &mut w,
                    &at(feature(x, y, r, 0.9), ms),
                    Vec2::ZERO,
                )
            };
            let seen = [
                admit(55.7, 2.5, 1.3, first_ms),
                admit(58.0, -3.5, 1.6, 80_600),
                admit(54.5, 7.4, 1.0, 80_800),
                admit(58.1, -3.6, 1.3, 86_000),
            ];
            (w, seen)
        };
        let (mover, rock) = (SONAR_ID_BASE, SONAR_ID_BASE + 1);
        let (w, seen) = fly(74_900);
        let o = |id: u16| w.obstacles().iter().find(|o| o.id == id).copied();
        let m = o(mover).map(|o| (o.shape.center(), o.velocity));
        assert!(
            m.is_some_and(|(c, v)| c == Vec2::new(54.5, 7.4) && v.x < 0.0 && v.y > 0.7),
            "the mover goes on from where it was seen: {m:?}"
        );
        // The jump opened a track of its own, which the rock seen again where it was updates:
        // still.
        assert_eq!(seen[3], Admission::Updated(rock));
        assert_eq!(o(rock).map(|o| o.velocity), Some(Vec2::ZERO));
        // A track seen once two sweeps before may be a rock the head missed: its jump stands,
        // and the nearer look is an object of its own.
        let (_, seen) = fly(63_000);
        assert_eq!(seen[1], Admission::Updated(mover));
        assert_eq!(seen[2], Admission::Added(rock));
    }

    #[test]
    fn a_second_look_in_the_same_pass_does_not_rate_a_small_track() {
        // Another vehicle (fits of 0.2 m) closing at 1 m/s, seen twice 1.2 s apart while this
        // one turned (0.6 m apart: fits of different faces), then a sweep later 9 m on: seen once after the hasty look, the third
        // sighting rates it at its velocity. Rated on the two looks it was still (the fits'
        // wander), and its tight gate missed the third sighting (generated head-on worlds).
        let cfg = TrackConfig::default();
        let fly = |r: f32| {
            let (mut w, mut t) = (World::new(), Tracks::default());
            let mut admit = |x: f32, ms: u64| {
                t.admit(
                    &cfg,
                    2.5,
                    &mut w,
                    &at(feature(x, 0.0, r, 0.9), ms),
                    Vec2::ZERO,
                )
            };
            admit(30.0, 0);
            assert_eq!(admit(29.4, 1200), Admission::Updated(SONAR_ID_BASE));
            let unrated = t.unrated(SONAR_ID_BASE);
            let third = t.admit(
                &cfg,
                2.5,
                &mut w,
                &at(feature(20.4, 0.0, r, 0.9), 10_200),
                Vec2::ZERO,
            );
            let v = w
                .obstacles()
                .iter()
                .find(|o| o.id == SONAR_ID_BASE)
                .map(|o| o.velocity);
            (unrated, third, v)
        };
        let (unrated, third, v) = fly(0.2);
        assert!(unrated, "two looks in one pass: seen once");
        assert_eq!(third, Admission::Updated(SONAR_ID_BASE));
        assert!(
            v.is_some_and(|v| (v - Vec2::new(-1.0, 0.0)).norm() < 0.05),
            "a sweep later it moves at 1 m/s: {v:?}"
        );
        // A rock-sized track (1 m) is rated by the second look, as before: its tight gate keeps
        // a neighbour's sighting from taking it over (`a_rock_seen_twice_...` above).
        let (unrated, _, _) = fly(1.0);
        assert!(!unrated);
    }

    fn glimpse(x: f32, y: f32, t_ms: u64) -> Feature {
        Feature {
            beams: 1,
            ..at(feature(x, y, 0.1, 0.0), t_ms)
        }
    }

    #[test]
    fn a_glimpse_a_sweep_later_rates_a_vehicle_seen_once_and_nothing_else() {
        // Another VideoRay seen once at 25 m, and a sweep later on one strong beam 9 m nearer
        // (generated head-on seed 93): the glimpse gives it its velocity.
        let (mut w, mut t) = (World::new(), Tracks::default());
        let mut admit =
            |w: &mut World, f: Feature| t.admit(&TrackConfig::default(), 2.5, w, &f, Vec2::ZERO);
        // Alone, a glimpse opens no track.
        assert_eq!(
            admit(&mut w, glimpse(10.0, 5.0, 0)),
            Admission::LowConfidence
        );
        let vehicle = at(feature(25.0, 0.0, 0.3, 0.9), 1000);
        assert_eq!(admit(&mut w, vehicle), Admission::Added(SONAR_ID_BASE));
        // In the same pass of the head it says nothing of the motion.
        assert_eq!(
            admit(&mut w, glimpse(22.0, 0.0, 2000)),
            Admission::LowConfidence
        );
        // A rock seen once, 9 m off the vehicle's way.
        let rock = at(feature(16.0, 9.0, 1.0, 0.9), 1000);
        assert_eq!(admit(&mut w, rock), Admission::Added(SONAR_ID_BASE + 1));
        // A sweep later: on the rock's face it is the rock; between the two, either could
        // have come there. Both are dropped, and nothing moves.
        assert_eq!(
            admit(&mut w, glimpse(16.0, 8.2, 10_000)),
            Admission::LowConfidence
        );
        assert_eq!(
            admit(&mut w, glimpse(20.0, 5.0, 10_000)),
            Admission::LowConfidence
        );
        assert_eq!(w.obstacles().len(), 2);
        assert!(w.obstacles().iter().all(|o| o.velocity == Vec2::ZERO));
        // Where only the vehicle could have come, it rates the vehicle.
        assert_eq!(
            admit(&mut w, glimpse(16.0, -3.0, 10_000)),
            Admission::Updated(SONAR_ID_BASE)
        );
        let v = w
            .obstacles()
            .iter()
            .find(|o| o.id == SONAR_ID_BASE)
            .map(|o| o.velocity);
        assert!(
            v.is_some_and(|v| (v - Vec2::new(-1.0, -1.0 / 3.0)).norm() < 0.05),
            "{v:?}"
        );
    }

    #[test]
    fn a_glimpse_between_two_tracks_waits_for_the_sweep_to_say_which_moved() {
        // Another VideoRay seen once at 25 m and a rock at 9 m off the way; a sweep later a
        // glimpse lies in both gates (generated head-on seed 111). When the head comes to the
        // rock again, a second later, and sees it where it was, the glimpse was the vehicle.
        let velocity = |w: &World, id: u16| {
            w.obstacles()
                .iter()
                .find(|o| o.id == id)
                .map(|o| o.velocity)
        };
        let fly = |rock_again_ms: u64| {
            let (mut w, mut t) = (World::new(), Tracks::default());
            let cfg = TrackConfig::default();
            let mut admit = |w: &mut World, f: Feature| t.admit(&cfg, 2.5, w, &f, Vec2::ZERO);
            admit(&mut w, at(feature(25.0, 0.0, 0.3, 0.9), 1000));
            admit(&mut w, at(feature(16.0, 9.0, 1.0, 0.9), 1000));
            assert_eq!(
                admit(&mut w, glimpse(20.0, 5.0, 10_000)),
                Admission::LowConfidence,
                "held"
            );
            assert_eq!(velocity(&w, SONAR_ID_BASE), Some(Vec2::ZERO));
            let rock = at(feature(16.0, 9.0, 1.0, 0.9), rock_again_ms);
            assert_eq!(admit(&mut w, rock), Admission::Updated(SONAR_ID_BASE + 1));
            (
                velocity(&w, SONAR_ID_BASE).unwrap_or_default(),
                velocity(&w, SONAR_ID_BASE + 1).unwrap_or_default(),
            )
        };
        let (vehicle, rock) = fly(11_000);
        assert!(
            (vehicle - Vec2::new(-5.0 / 9.0, 5.0 / 9.0)).norm() < 0.05,
            "{vehicle:?}"
        );
        assert!(rock.norm() < 0.05, "{rock:?}");
        // Held no longer than `revisit_ms`: then it is dropped, and nothing moves.
        let (vehicle, rock) = fly(15_000);
        assert_eq!((vehicle, rock), (Vec2::ZERO, Vec2::ZERO));
    }

    fn faint(x: f32, y: f32, t_ms: u64) -> Feature {
        Feature {
            faint: true,
            ..glimpse(x, y, t_ms)
        }
    }

    #[test]
    fn two_faint_sightings_on_a_collision_course_open_a_mover_and_one_alone_nothing() {
        // Another VideoRay coming head-on at 1 m/s, on one weak beam a sweep (module notes,
        // "Faint pairs"); this vehicle comes at it at 1 m/s too.
        let (mut w, mut t, cfg) = (World::new(), Tracks::default(), TrackConfig::default());
        t.own_velocity(Vec2::new(1.0, 0.0));
        let first = faint(15.0, 0.0, 1000);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &first, Vec2::ZERO),
            Admission::LowConfidence
        );
        assert!(w.obstacles().is_empty(), "one faint sighting is nothing");
        let own = Vec2::new(3.2, 0.0);
        let second = faint(11.8, 0.0, 4200);
        let id = match t.admit(&cfg, 2.5, &mut w, &second, own) {
            Admission::Added(id) => id,
            other => panic!("{other:?}"),
        };
        let velocity = |w: &World| {
            w.obstacles()
                .iter()
                .find(|o| o.id == id)
                .map(|o| o.velocity)
        };
        assert!(velocity(&w).is_some_and(|v| (v - Vec2::new(-1.0, 0.0)).norm() < 0.01));
        // Its next look, faint too, updates it.
        let third = faint(8.8, 0.1, 7400);
        let own = Vec2::new(6.4, 0.0);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &third, own),
            Admission::Updated(id)
        );
        assert_eq!(w.obstacles().len(), 1);
        // Borne out by nothing for two sweeps more, it goes (a rock's sighting comes then).
        let rock = at(feature(-30.0, 0.0, 1.0, 0.9), 7400 + 7001);
        t.admit(&cfg, 2.5, &mut w, &rock, own);
        assert!(w.obstacles().iter().all(|o| o.id != id));
        assert!(t.tracks().iter().all(|k| k.id != id));
        // A faint sighting by what is believed is its edge: it is kept for no pair.
        let (mut w, mut t) = (World::new(), Tracks::default());
        t.own_velocity(Vec2::new(1.0, 0.0));
        let rock = at(feature(12.0, 0.0, 1.0, 0.9), 0);
        assert_eq!(
            t.admit(&cfg, 2.5, &mut w, &rock, Vec2::ZERO),
            Admission::Added(SONAR_ID_BASE)
        );
        for (x, t_ms) in [(10.5, 1000), (7.5, 4200)] {
            let f = faint(x, 0.0, t_ms);
            assert_eq!(
                t.admit(&cfg, 2.5, &mut w, &f, Vec2::ZERO),
                Admission::LowConfidence
            );
        }
        assert_eq!(w.obstacles().len(), 1);
    }
}
