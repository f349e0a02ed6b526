//! One performance in two files (issue 44), beyond CMU 02_03
//! (`mocap::one_capture`): CMU 02_01, 02_02 and 02_03 as the native AMC
//! and as the Reallusion CC-rig BVH conversions (`cmu-bvh-ccrig`), and
//! 01_01 as the AMC and the cgspeed BVH, each pair aligned in time (the
//! BVH frame matching an AMC frame by the knees' bend), retargeted onto
//! one character as `retarget` reads them, and compared: the mean over
//! frames and canonical joints of the distance between the two results,
//! over the character's height (`abs`), and the same about the pelvis
//! (`rel`, the posture alone).
//!
//! What differs between the two files (measured 2026-11-30, session 22,
//! before the retarget, both clips in metres, Y up, 30 fps):
//! - Frame rate and time: 120 vs 60 fps; aligned by the knees to 1.2°.
//! - Bone lengths: the CC rig's legs are 1.164 times the subject's; per
//!   bone over that ratio the hips' offset is 0.60 (a narrower pelvis), the
//!   neck 2.0 and head 0.39 (joints placed elsewhere on the same line),
//!   upper arms 0.93-0.96, forearms 0.76-0.79: the kernel takes limb
//!   directions, not lengths, so these move little.
//! - The root: travel 1.144-1.148 times the AMC's (1.6 % short of the
//!   legs), no vertical motion (the AMC's pelvis rises and falls 15 cm a
//!   stride on 02_03).
//! - The reference: the AMC's ASF rest skeleton (pelvis → chest 2.8° off
//!   the vertical, knees straight); the BVH's most neutral frame (02_03:
//!   frame 34, pelvis → chest 5.4°, knees bent 37°; 02_01: frame 65, 4.7°):
//!   the conversion keeps the knees bent under the AMC's root height.
//!
//! After the retarget (02_03, mean % of the height per joint, abs):
//! pelvis 2.13 (horizontal 1.57, growing with the travel to 4.1 cm at the
//! end; vertical 1.16), chest 3.32, neck 3.85, head 4.09, shoulders
//! 3.5-4.1, toes 2.5-3.3; the per-frame mean grows from 2.0 to 3.9 %. The
//! upper body carried most of it: the two references' lean (2.6° apart on
//! the pelvis → chest line) turned the whole torso, and the neck and head
//! above it, by that much.
//!
//! The change (session 22): the torso's rotations are measured from the
//! reference stood upright on its pelvis → chest line
//! (`pose::retarget` kernel, `level_torso`). 02_03 2.97 → 2.26 %
//! (chest 3.32 → 1.89, head 4.09 → 2.60), 02_01 3.08 → 1.90 %, 02_02 →
//! 2.20 %, 01_01 0.00 → 0.00. Left: the pelvis (2.1-2.5 %: the travel's
//! 1.6 % and the root height stood on the legs) and the posture about it
//! (`rel` 1.3-1.9 %, most in the feet and toes: the BVH's reference has
//! its knees bent).
//!
//! Session 23 (measured with a scratch kernel, not kept; see the
//! session's report): a reference stood on straight legs (each shin
//! turned onto its thigh's line, the foot with it) took 02_03 from 2.26
//! to 2.12 % (about the pelvis 1.92 → 1.83, the pelvis 2.15 → 2.10),
//! 02_02 2.20 → 2.18, 02_01 1.90 → 1.92. What remains then, per joint
//! (02_03, abs / about the pelvis, %): the pelvis 2.10 (horizontal 1.57,
//! the travel; vertical 1.16), head 2.46 / 3.01, neck 2.07 / 2.40, left
//! arm 2.05-2.22 / 2.54-2.86, right ankle and toe 2.39 / 2.66 and
//! 2.37 / 2.48: the neck, head and left arm about the pelvis carry as
//! much as the feet. The same BVH turned 30° and scaled by 1.37 kept
//! the posture (1.83 %) but not the pelvis's height (vertical 1.30
//! against 1.16): the 3 cm contact band does not scale with the clip.
//!
//! Session 24: the contact band is a fraction of the clip's leg (3.6 %),
//! so the turned and rescaled copy retargets exactly as the BVH (before:
//! the pelvis 2.17 against 2.15 %, vertically 1.28 against 1.17); 02_03
//! 2.26 → 2.31 % (the pelvis's vertical 1.17 → 1.23: the CC rig's band
//! is now 3.5 cm), 02_01 1.90, 02_02 2.20 unchanged. Measured with a
//! scratch kernel (`SM44_*` switches, not kept): the two files' limb
//! directions agree within 0.3-2.6° (mean over frames: upper arms
//! 0.3-1.0, forearms 0.4-1.1, thighs 1.2-2.6, shins 0.8-1.7; heading
//! 1.2° apart), so what remains is the kernel's, not the data's: the
//! bones that differ are the ones whose joints sit elsewhere (pelvis →
//! hips 37-39°, spine 18-20°, head 14°, clavicles 13°, feet 7-10°), and
//! the BVH's reference (a frame) carries its stride: hips turned 8.2°
//! against the shoulders in 02_03's frame 34, knees bent 35-37°. Rules
//! tried (02_01 / 02_02 / 02_03, abs %; main 1.905 / 2.196 / 2.262):
//! knees of the reference straightened 1.915 / 2.183 / 2.122 (fails
//! `mocap::one_capture`'s zeroed-root run_normal, 0.90 → 1.00 %);
//! hips and shoulders of the reference squared to their mean line
//! 1.784 / 2.152 / 2.430 (02_03's hips about the pelvis 0.95 / 0.62 →
//! 0.28 / 0.22, but chest, neck and arms worse); feet turned to the
//! clip's planted yaw 1.832 / 2.141 / 2.310; travel and height scaled by
//! the hip's standing height (legs and ankle over toe) 1.832 / 2.319 /
//! 2.342 (the pelvis horizontally 1.57 → 0.91 on 02_03).
//!
//! Session 25: where the reference is a frame (the CC BVHs', Bandai's),
//! its torso is the clip's mean carriage in the body's heading frame
//! (`pose::retarget`'s `motion_ref`: each torso joint's mean place about
//! the pelvis, the file joints' mean rotations). 02_01 / 02_02 / 02_03
//! 1.905 / 2.196 / 2.309 → 1.805 / 2.066 / 2.116 % (about the pelvis
//! 1.31 / 1.48 / 1.92 → 1.28 / 1.40 / 1.59); the turned and rescaled
//! copy still equals the BVH's. Measured with a switched build and not
//! kept (abs %): the hips' and shoulders' lines alone turned to their
//! mean yaw 1.920 / 2.196 / 2.231; the mean torso places without the file
//! rotations' mean 1.877 / 2.093 / 2.473 (the chest then turns from the
//! frame's file rotation, no longer matching its places); the mean
//! carriage with the knees straightened 1.855 / 2.098 / 1.960; with the
//! travel scaled by the standing hip height 1.765 / 2.260 / 2.118. What
//! remains (02_03, signed means in the AMC result's heading frame, % of
//! the height): the BVH's pelvis 1.4 behind the AMC's (the travel 1.6 %
//! short, above) and 1.2 lower, while every other joint about the pelvis
//! sits 0.8-2.5 ahead (spine 0.8, chest 0.9, head 2.3, knees 1.0-1.3,
//! ankles 1.6-1.8, toes 1.9-2.5): the CC rig's hips sit behind the
//! AMC's relative to the feet (its thighs 1.2-2.6° further forward, the
//! data's), and the two offsets cancel in part in the world.
//!
//! Session 26: the pelvis placed by the body, measured and not kept (the
//! kernel unchanged; these figures are the main kernel's results moved
//! horizontally per frame in a scratch copy of this test, and a scratch
//! kernel with `SM44_PLACE`/`SM44_START` switches whose `root` setting
//! wrote 02_02's PC2 on samba byte for byte as main's). Main: 02_01 /
//! 02_02 / 02_03 1.802 / 2.064 / 2.110 % (the pelvis 2.14 / 2.42 / 2.16).
//! An anchor of the body (the root; the hips' midpoint; the feet, ankles
//! and toes; the legs' eight joints; all nineteen joints) following the
//! clip's same anchor from the character's rest one, its travel scaled by
//! the legs' ratio, the standing hip height (median or 90th percentile of
//! the hips' midpoint over the lowest foot joint) or the hip → ankle
//! extension (90th percentile): the best per pair were the root by the
//! extension 1.736 / 1.967 / 2.070, the mean joint by the hip height
//! 1.800 / 2.058 / 1.866, the legs' mean by the hip height 2.012 / 2.295 /
//! 1.822; the hips' midpoint by the legs 2.161 / 2.476 / 2.242, the feet by
//! the legs 2.372 / 2.785 / 3.310. The hip height's scale takes the
//! pelvis to 1.36 / 1.43 / 1.61 but moves the body about it further off.
//! Foot locking in the kernel (where a clip foot touches its ground and
//! its stiller joint, ankle or toe, moves under 2 % of the leg a frame,
//! the character's same joint moves as the clip's, scaled; the shift held
//! in the air): 1.99 / 3.62 / 2.14 %, re-timed 4.40 (the pelvis 1.63 /
//! 2.63 / 1.78); it changes every clip's output (02_02 on samba: 74 of 75
//! frames, up to 21.4 cm at the end; on this test's character the locked
//! feet moved 02_02's body 4.3 cm from the scaled root by the end with the
//! AMC, 14.1 cm with the BVH) and fails
//! `mocap::one_capture`'s zeroed-root test. With frame 0 placed by the
//! mean joint (`SM44_START=centroid`): root 2.17 / 2.56 / 2.46, foot
//! locking 1.63 / 2.71 / 2.04. None is near 1 %: about the pelvis the two
//! results stay 1.28 / 1.40 / 1.59 % apart whatever the placement (every
//! rule above moves the whole body), so the gap left is the posture's
//! (the CC rig's thighs and hips, above) and the pelvis's height on bent
//! knees, not the root's travel.
//!
//! Session 27: the posture about the pelvis decomposed (scratch test and
//! a switched kernel, not kept; main's kernel). `rel` on main 1.278 /
//! 1.395 / 1.594 % (02_01 / 02_02 / 02_03). Per joint rotation: the BVH's
//! result given the AMC result's rotation of one group (the chain from
//! the pelvis re-built on the character), the drop of `rel`: the pelvis
//! 0.34 / 0.37 / 0.35, spine 0.16 / 0.09 / 0.08, chest 0.18 / 0.32 / 0.32,
//! neck and head 0.01-0.02, arms 0.01-0.05, thighs 0.20 / 0.18 / 0.31,
//! shins 0.08-0.09, feet 0.03 / 0.02 / 0.12; the pelvis, spine and chest
//! together 0.69 / 0.79 / 0.76 (0.59 / 0.61 / 0.83 left, all in the legs);
//! the legs together 0.29 / 0.30 / 0.54; the results' heading 0.00-0.01.
//! Per cause: (a) the reference: the AMC measured as the BVH is (its most
//! neutral frame, the mean carriage) 1.250 / 1.018 / 1.234 (a share of
//! 0.03 / 0.38 / 0.36; that rule alone moves the AMC's own result 0.34 /
//! 0.64 / 0.58); (b) bone lengths: the BVH re-built on the AMC's
//! proportions (scaled by the legs), its directions kept, 1.55 / 1.68 /
//! 1.88, further (the levelling line and the mean carriage read lengths);
//! (c) the hips inside the pelvis: the AMC's (scaled) at ±0.109, −0.114,
//! +0.05 m in the frame of the hips' line and the spine, the CC rig's at
//! ±0.097, −0.022, +0.006 (9 cm higher, 4.5 cm back); the AMC's hips put
//! where the CC rig's are (knees kept) 1.161 / 1.237 / 1.439 (the upper
//! body nearer through the pelvis's fit, the knees further), the BVH's
//! where the AMC's are 1.82 / 1.98 / 2.25; (d) the spine's bend: over the
//! frames the CC rig's pelvis → spine bone is pitched 18-20° from the
//! AMC's, its spine → chest bone 11° the other way, the pelvis → chest
//! line 2.6-3.5° apart. The pelvis's rotation from the frame of the hips'
//! line and the spine bone (not the fit to the three directions, where the
//! AMC's low hips weigh in its pitch and the CC rig's level hips do not):
//! `rel` 1.127 / 1.182 / 1.376, abs 1.82 / 2.08 / 2.08 (the pelvis 2.15 /
//! 2.43 / 2.13 is most of abs); from the hips' line and the pelvis →
//! chest line 1.07 / 1.15 / 1.34, abs 1.82 / 2.09 / 2.08; neither gains
//! with both files measured from a frame (1.248 / 1.011 / 1.231). Not kept:
//! not run on the other groups. The mirrored pair (both files reflected
//! left for right) gives the plain pair's figures to 1e-3 of the height.
//!
//! Session 28: the pelvis's own gap decomposed (`pose::travel`): along the
//! travel a drift of the two scales (the kernel's legs, 1.1638, against
//! the conversion's standing hip height, 1.1446 / 1.1452 / 1.1473), across
//! it 0.6-0.8 % plus the travel headings 0.5-0.6° apart, up 0.2 / 0.25 /
//! −1.2 %. The travel's scale measured in the kernel (scratch switches,
//! not kept; abs / the pelvis %, 02_01 / 02_02 / 02_03; the mirrored pair
//! equal to 02_03 in every row): the legs (main) 1.81 / 2.07 / 2.12, the
//! pelvis 2.15 / 2.43 / 2.15; the hips' standing height (90th percentile of
//! the hips' midpoint over the lowest foot joint, against the character's
//! rest) 1.91 / 2.11 / 2.39, the pelvis 1.26 / 1.37 / 1.44; with the
//! pelvis-frame rule of session 27 1.82 / 1.98 / 2.21; the hip → ankle
//! extension (90th percentile) 1.70 / 1.94 / 2.07 (frame rule 1.70 / 1.94
//! / 1.98), but that lengthens every clip's travel 1-4 % (the AMC's too:
//! it does not undo the conversion's scale, BVH / AMC 1.003); the knee over
//! its foot 2.82 / 3.24 / 3.25; the travel fitted to keep the result's
//! lowest foot joint still 2.77 / 2.42 / 2.12 (the fit reads 0.95-0.97 on
//! both files of 02_01 and 02_02, 0.71 on 02_03: the rolling foot).
//!
//! Session 29: the posture about the pelvis per group and per axis
//! (printed by this test: the gap about the pelvis left when the BVH's
//! result takes the AMC result's rotations of one group, re-built on the
//! character from the pelvis; and each torso joint's rotation in the two
//! results apart, mean signed degrees about the AMC body's left-right /
//! forward / vertical axes). Main's kernel, `rel` 1.28 / 1.40 / 1.59
//! (02_01 / 02_02 / 02_03): the BVH's pelvis turned +7.1 / +7.3 / +7.0°
//! about the left-right axis (further forward), −1.0 / −1.1 / −1.1 and
//! −0.8 / −0.5 / +0.7° about the others; the spine +1.4 / +0.8 / +0.6°,
//! the chest (and the neck and head on it) +2.1 / +3.8 / +3.9°. Given
//! the AMC's rotations of one group, `rel` becomes: the pelvis 0.94 /
//! 1.02 / 1.24, the spine 1.12 / 1.30 / 1.51, the chest 1.10 / 1.08 /
//! 1.28, the neck and head 1.27 / 1.37 / 1.57, the arms 1.21 / 1.33 /
//! 1.54, the thighs 1.08 / 1.22 / 1.29, the shins 1.19 / 1.32 / 1.51, the
//! feet 1.25 / 1.38 / 1.47; the trunk (pelvis, spine, chest) 0.59 / 0.61
//! / 0.83, the legs 0.99 / 1.10 / 1.05. The pelvis's 7° is the fit to its
//! three bones weighing where the rigs put the hip and spine joints
//! inside the pelvis (the CC rig's hips 9 cm higher and 4.5 cm back, its
//! pelvis → spine bone 18-20° off the AMC's). The rest pose (T against
//! A) does not reach the limbs (they take directions); the reference
//! rule (the ASF rest against the BVH's mean carriage) is the candidate
//! for the chest's 2-4° (session 27 measured its share at 0.03 / 0.38 /
//! 0.36; not measured again).
//!
//! Rules measured with a switched build (not kept; abs / rel / the
//! pelvis %, 02_01 / 02_02 / 02_03; the mirrored pair equal to 02_03 in
//! every row, 01_01 0.00): the pelvis by the frame of the hips' line and
//! the pelvis → chest line: 1.82 / 2.09 / 2.08, rel 1.07 / 1.15 / 1.34, the
//! pelvises +2.6 / +1.7 / +1.5° apart (what remains given the AMC's
//! rotations: the pelvis 0.94 / 1.02 / 1.24, the chest 0.90 / 0.84 / 1.05,
//! the thighs 0.81 / 0.90 / 0.98, the trunk 0.59 / 0.61 / 0.83, the legs
//! 0.68 / 0.73 / 0.68); with the hip-height travel (`pose::travel`) on top
//! 1.78 / 1.96 / 2.19 (the pelvis 1.27 / 1.39 / 1.39); main with that
//! travel 1.91 / 2.11 / 2.39. With the spine turning with that pelvis
//! (the trunk as one line) 1.90 / 2.19 / 2.11, rel 1.22 / 1.32 / 1.48;
//! the spine halfway between the pelvis and the chest 1.82 / 2.13 /
//! 2.09, rel 1.18 / 1.40 / 1.58. The pelvis by the frame of the hips'
//! line and the pelvis → spine bone (session 27's): 1.82 / 2.08 / 2.08,
//! rel 1.13 / 1.18 / 1.38, the pelvises +3.8 / +2.5 / +2.2° apart; not
//! kept either (yardstick head p95 / velocity error 02_02 4.0 / 0.119 →
//! 5.8 / 0.122, 03_01 → 5.5 / 0.078, 03_02 3.4 / 0.129 → 3.7 / 0.145,
//! 02_03 → 3.9 / 0.192, 131_01 ground penetration 1.45 → 3.21 cm). The pelvis-and-chest-line frame passes
//! `pose::`, `mocap::`, `drive::`, `jobs::` (CI=true) but is not kept:
//! it turns the pelvis with the upper trunk's bend, and on one rig the
//! result moves away from its clip: the yardstick (samba) head p95 / joint
//! velocity error 02_02 4.0 / 0.119 → 6.2 / 0.122, 03_01 4.1 / 0.072 →
//! 5.5 / 0.078, 02_03 1.8 / 0.184 → 4.1 / 0.195, 131_02 velocity 0.078 →
//! 0.086; the FBX files' 01_01 head p95 15.4 → 21.3, Samba Dancing 9.6 →
//! 12.1 (velocity 0.154 → 0.175). The 1 % is not reached by any rule: the
//! pelvis's own gap (the travel's scale, 1.3-1.4 % at best) and the
//! posture with the whole trunk given (0.59 / 0.61 / 0.83 about the
//! pelvis, most of it the legs' directions) each leave too little for the
//! other.
//!
//! Session 30: the reference rule, an option (`SURFMOTION_REFERENCE=
//! carriage`, read once per process; default `rest`): an upright rest
//! skeleton's torso replaced by the clip's mean carriage too, so both
//! files of a performance measure the torso from their own mean carriage
//! and the CC rig's forward-tipped pelvis bones are read as its carriage,
//! not as a pose. This test with it (abs / rel / the pelvis %, 02_01 /
//! 02_02 / 02_03; main in brackets): 1.85 / 2.05 / 2.07 (1.81 / 2.07 /
//! 2.12), rel 1.24 / 1.02 / 1.21 (1.28 / 1.40 / 1.59), the pelvis 2.15 /
//! 2.43 / 2.15 (unchanged: the travel); the mirrored, turned and
//! re-ordered copies equal 02_03, 01_01 0.00. The torso's rotations apart
//! about the left-right axis: the pelvis +2.6 / +1.7 / +1.6° (+7.1 / +7.3
//! / +7.0), the chest +2.6 / +1.7 / +1.5° (+2.1 / +3.8 / +3.9), every
//! torso joint now the same (the two mean carriages' lean apart). Given
//! the AMC's rotations of the legs, rel 0.84 / 0.60 / 0.56 (0.99 / 1.10
//! / 1.05). Not the default: each AMC clip's own result moves (the
//! yardstick on samba, head p95 °, velocity error cm/frame, penetration
//! cm; main → carriage): 131_01 14.1, 0.230, 1.45 → 14.1, 0.235, 1.47;
//! 131_02 10.9 → 13.2; 02_02 4.0, 0.119 → 4.3, 0.122; 03_01 4.1 → 4.2;
//! 03_02 3.4, 0.129, 1.40 → 5.0, 0.078, 0.92; 02_03 1.8, 0.184, 2.79 →
//! 2.2, 0.188, 2.44; the Bandai clips (frame references already)
//! unchanged; no warning added. The FBX files (head p95, velocity error):
//! 01_01 15.4, 0.085 → 14.5, 0.080; Samba Dancing 9.6, 0.154 → 10.6,
//! 0.158; the barbarian 3.8, 0.029 → 3.3, 0.026 (its vertex off its ring
//! by 5.9 cm no longer warned); Kenney unchanged. The head's p95 rises on five of six CMU
//! clips (within their lines), abs improves on two pairs of three,
//! `pose::`/`mocap::` with it: 41 passed, 1 failed
//! (`pose::toes::toes_in_the_air_stay_with_the_foot`: a swung leg's toe no
//! longer turns with its ankle within 1e-9), `drive::` 14 and `jobs::` 37
//! passed with it (CI=true). Looked (03_02 frame 85, the largest change, 19.1 cm,
//! stepping up onto the block): main's trunk and head lean forward over
//! the raised knee, the option's stand upright, and its skirt's front
//! panel juts out before the knee in a thin flap; legs and feet alike.
//!
//! Earlier figures (measured 2026-11-29):
//! - 01_01: the cgspeed BVH retargets as the AMC does (0.00 %).
//! - The CC conversions: 3.1-4.2 % apart, 1.7-2.7 % of it posture. The
//!   pelvis alone is 2.1-2.5 %: the conversion scaled the root's travel
//!   by 1.144-1.148 (the same on all three clips) while the CC rig's legs
//!   are 1.164 times the subject's, and the kernel scales the travel by
//!   the legs; and the conversion dropped the root's vertical channel,
//!   which `root_from_legs` stands on the planted foot again.
//! - The posture: the AMC's reference is its ASF rest skeleton, whose
//!   hip → shoulder line stands 6.9° off the vertical (the run's frames
//!   3.9° on average), the conversion's the most neutral frame. A
//!   scratch variant of the kernel that levelled every reference by that
//!   line brought `rel` to 0.7-1.15 % on the CC pairs but took 01_01 from
//!   0.00 to 0.78 % (the cgspeed BVH drops the thorax's length: its
//!   shoulders sit elsewhere); levelled by the pelvis → chest line (the
//!   kernel since session 22) 01_01 stays at 0.00 %.
//! - The travel per stride, tried and not kept (session 21): `k`, the
//!   least-squares ratio of the root's horizontal step to the step of the
//!   root relative to the least-moving foot joint (ankle or toe, moving
//!   under 2 % of the leg per frame), over 30 fps frames, was meant to
//!   find the conversion's travel 1.6 % short of its legs and scale it
//!   back. It reads 1.056 on the 02_03 AMC and 1.074 on its CC BVH: a
//!   capture is 5.6 % off 1 by this estimate (the "planted" joint rolls
//!   with the body), and the two files differ the wrong way (1.0165
//!   instead of 0.985). With the kernel scaling travel by `s / k` when `k`
//!   is more than 1 % off 1, 02_03's pelvis went from 2.1 % to 3.47 % of
//!   the height apart, 02_01's abs from 3.1 % to 4.4 %. The next try needs
//!   a foot anchor that does not roll (heel or the sole's contact point).

use crate::common;

use glam::DQuat;
use surfmotion::mocap::Clip;
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{ClipPoses, clip_poses, ground_tilt, leg_length, retarget};
use surfmotion::rig::{Canonical, detect_clip, load_clip};

use Canonical as C;

fn knees(p: &Pose) -> [f64; 2] {
    let k = |h: C, k: C, a: C| {
        let (h, k, a) = (p[h.index()], p[k.index()], p[a.index()]);
        (k - h).angle_between(a - k).to_degrees()
    };
    [
        k(C::LHip, C::LKnee, C::LAnkle),
        k(C::RHip, C::RKnee, C::RAnkle),
    ]
}

fn drop_frames(c: &Clip, n: usize) -> Clip {
    let j = c.joint_count();
    c.clone()
        .edited(|p| {
            p.rotations.drain(..n * j);
            p.translations.drain(..n * j);
        })
        .unwrap()
}

/// The two clips from the same instant: BVH frame `k ≥ skip` is AMC frame
/// `ratio · (k − skip) + o`, the pair (skip, o) whose knees' bend differ
/// least (mean degrees, also returned).
/// CMU 02_01, 02_02 and 02_03 as the AMC and the CC-rig BVH conversion,
/// then 02_03's pair mirrored and turned (the variants of [`varied`]).
pub(super) const CC_PAIRS: [(&str, &str, &str); 5] = [
    ("cmu-amc/02/02_01.amc", "cmu-bvh-ccrig/002_01.bvh", ""),
    ("cmu-amc/02/02_02.amc", "cmu-bvh-ccrig/002_02.bvh", ""),
    ("cmu-amc/02/02_03.amc", "cmu-bvh-ccrig/002_03.bvh", ""),
    (
        "cmu-amc/02/02_03.amc",
        "cmu-bvh-ccrig/002_03.bvh",
        "mirrored",
    ),
    ("cmu-amc/02/02_03.amc", "cmu-bvh-ccrig/002_03.bvh", "turned"),
];

/// One capture's two files under the mocap folder `m` (`a` the AMC, `b`
/// the BVH conversion), each in metres Y-up: as loaded (`amc`, `bvh`) and
/// aligned in time by [`aligned`] (`al`, `bl`).
pub(super) struct TwoFiles {
    pub amc: Clip,
    pub bvh: Clip,
    pub al: Clip,
    pub bl: Clip,
}

pub(super) fn two_files(m: &std::path::Path, a: &str, b: &str) -> TwoFiles {
    let mut amc = load_clip(&m.join(a), &Default::default()).unwrap();
    let mut bvh = load_clip(&m.join(b), &Default::default()).unwrap();
    amc.to_metres_y_up();
    bvh.to_metres_y_up();
    let (al, bl, _) = aligned(&amc, &bvh);
    TwoFiles { amc, bvh, al, bl }
}

/// A clip's canonical poses at 30 fps, its rig detected.
pub(super) fn poses_at_30(c: &Clip) -> ClipPoses {
    let c = c.try_resampled(30.0).unwrap();
    let map = detect_clip(&c).unwrap().map;
    clip_poses(&c, &map).unwrap()
}

/// The two-file tests' variants of a pair: `"mirrored"` mirrors both,
/// `"turned"` turns the second 30° about the vertical and scales it by
/// 1.37, anything else leaves them. Also the rotation that turns the
/// second's results back (identity unless turned).
pub(super) fn varied(ca: ClipPoses, cb: ClipPoses, variant: &str) -> (ClipPoses, ClipPoses, DQuat) {
    let q = DQuat::from_rotation_y(30f64.to_radians());
    match variant {
        "mirrored" => (mirrored(ca), mirrored(cb), DQuat::IDENTITY),
        "turned" => (ca, turned(cb, q, 1.37), q.inverse()),
        _ => (ca, cb, DQuat::IDENTITY),
    }
}

pub(super) fn aligned(amc: &Clip, bvh: &Clip) -> (Clip, Clip, f64) {
    let ratio = (amc.fps() / bvh.fps()).round() as i64;
    let pa = detect_clip(amc).unwrap().map.poses(amc).unwrap();
    let pb = detect_clip(bvh).unwrap().map.poses(bvh).unwrap();
    let mut best = (0i64, 0i64, f64::MAX);
    for skip in 0..3i64 {
        for o in 0..=8i64 {
            let (mut s, mut n) = (0.0, 0);
            for (k, b) in pb.iter().enumerate().skip(skip as usize) {
                let i = ratio * (k as i64 - skip) + o;
                if let Some(a) = pa.get(i as usize) {
                    let (x, y) = (knees(a), knees(b));
                    s += (x[0] - y[0]).abs() + (x[1] - y[1]).abs();
                    n += 1;
                }
            }
            let g = s / (2 * n.max(1)) as f64;
            if g < best.2 {
                best = (skip, o, g);
            }
        }
    }
    (
        drop_frames(amc, best.1 as usize),
        drop_frames(bvh, best.0 as usize),
        best.2,
    )
}

/// Stands for the re-ordered copy of 02_03's CC BVH in the table of pairs.
const REORDERED: &str = "002_03 with its rotation channels re-ordered";

/// Stands for 02_03's CC BVH turned 30° about the vertical and scaled by
/// 1.37 (its poses, reference and file rotations) in the table of pairs.
const TURNED: &str = "002_03 turned and rescaled";

/// Stands for 02_03's CC BVH re-timed (resampled from 60 to 24 fps
/// before it is read as usual) in the table of pairs.
const RETIMED: &str = "002_03 re-timed to 24 fps";

/// Stands for 02_03's AMC and CC BVH both mirrored left for right (each
/// pose reflected across the sagittal plane, its left and right joints
/// swapped, and the file joints' rotations with them) in the table of
/// pairs.
const MIRRORED: &str = "002_03 mirrored, with its AMC";

/// The joint on the other side (itself for the torso's).
pub(super) fn other_side(c: C) -> C {
    match c {
        C::LShoulder => C::RShoulder,
        C::LElbow => C::RElbow,
        C::LWrist => C::RWrist,
        C::LHip => C::RHip,
        C::LKnee => C::RKnee,
        C::LAnkle => C::RAnkle,
        C::LToe => C::RToe,
        C::RShoulder => C::LShoulder,
        C::RElbow => C::LElbow,
        C::RWrist => C::LWrist,
        C::RHip => C::LHip,
        C::RKnee => C::LKnee,
        C::RAnkle => C::LAnkle,
        C::RToe => C::LToe,
        c => c,
    }
}

/// `cp` mirrored across the plane x = 0 (the clip's, metres, Y up): each
/// pose's joints reflected and swapped left for right, and the file
/// joints' world rotations `R` with them (`M R M`, `M` the reflection: a
/// quaternion's y and z negated).
pub(super) fn mirrored(mut cp: ClipPoses) -> ClipPoses {
    let flip = |p: &Pose| {
        let mut o = *p;
        for c in Canonical::ALL {
            let x = p[c.index()];
            o[other_side(c).index()] = glam::DVec3::new(-x.x, x.y, x.z);
        }
        o
    };
    for p in cp.poses.iter_mut().chain([&mut cp.reference.pose]) {
        *p = flip(p);
    }
    let rotations: Vec<_> = cp
        .reference
        .rotations
        .iter()
        .map(|w| {
            let mut o = *w;
            for c in Canonical::ALL {
                o[other_side(c).index()] =
                    w[c.index()].map(|q| DQuat::from_xyzw(q.x, -q.y, -q.z, q.w));
            }
            o
        })
        .collect();
    cp.reference.rotations = rotations.into();
    cp
}

/// `cp` turned by `q` and scaled by `k` about the origin: the poses, the
/// reference's pose and the file joints' world rotations.
pub(super) fn turned(mut cp: ClipPoses, q: DQuat, k: f64) -> ClipPoses {
    for p in cp.poses.iter_mut().chain([&mut cp.reference.pose]) {
        *p = p.map(|x| q * x * k);
    }
    let rotations: Vec<_> = cp
        .reference
        .rotations
        .iter()
        .map(|w| w.map(|r| r.map(|r| q * r)))
        .collect();
    cp.reference.rotations = rotations.into();
    cp
}

/// `path` (a BVH) written again with every joint's rotation channels in
/// the order X Y Z, its rotations unchanged (`target/tmp/fixtures`).
fn reordered_channels(path: &std::path::Path) -> std::path::PathBuf {
    let out = common::fixture_dir("two_files_reordered").join("002_03_xyz.bvh");
    let changed = common::bvh::in_xyz_order(path, &out);
    assert!(changed > 10, "only {changed} joints re-ordered");
    out
}

/// A result's global joint rotations per frame.
type Rotations = [DQuat; Canonical::COUNT];

/// The joints whose rotations [`posture_shares`] swaps, by group.
const GROUPS: [(&str, &[C]); 10] = [
    ("the pelvis", &[C::Pelvis]),
    ("the spine", &[C::Spine]),
    ("the chest", &[C::Chest]),
    ("the neck and head", &[C::Neck, C::Head]),
    ("the arms", &Canonical::ARMS),
    ("the thighs", &[C::LHip, C::RHip]),
    ("the shins", &[C::LKnee, C::RKnee]),
    ("the feet", &[C::LAnkle, C::RAnkle, C::LToe, C::RToe]),
    (
        "the trunk (pelvis, spine, chest)",
        &[C::Pelvis, C::Spine, C::Chest],
    ),
    (
        "the legs",
        &[
            C::LHip,
            C::RHip,
            C::LKnee,
            C::RKnee,
            C::LAnkle,
            C::RAnkle,
            C::LToe,
            C::RToe,
        ],
    ),
];

/// The mean distance about the pelvis (over frames and joints, over `h`)
/// between `a`'s poses and `b`'s re-built on `character` from the pelvis
/// with `b`'s global rotations, those of `swap` taken from `a`.
fn rebuilt_rel(
    character: &Pose,
    a: &[(Pose, Rotations)],
    b: &[(Pose, Rotations)],
    swap: &[C],
    h: f64,
) -> f64 {
    let p = C::Pelvis.index();
    let mut sum = 0.0;
    for ((pa, qa), (pb, qb)) in a.iter().zip(b) {
        let mut g = *qb;
        for c in swap {
            g[c.index()] = qa[c.index()];
        }
        let mut t = [glam::DVec3::ZERO; Canonical::COUNT];
        t[p] = pb[p];
        for c in Canonical::ALL {
            if let Some(q) = c.parent() {
                let (j, k) = (c.index(), q.index());
                t[j] = t[k] + g[k] * (character[j] - character[k]);
            }
            sum += (pa[c.index()] - pa[p]).distance(t[c.index()] - t[p]);
        }
    }
    sum / (a.len() * Canonical::COUNT) as f64 / h
}

/// What each group's rotations carry of the posture's gap: the gap about
/// the pelvis re-built from the BVH result's own rotations (returned, it
/// must equal the measured one), and printed per group the gap left when
/// the BVH's result takes the AMC's rotations of that group (% of `h`).
fn posture_shares(
    character: &Pose,
    a: &[(Pose, Rotations)],
    b: &[(Pose, Rotations)],
    h: f64,
) -> (f64, String) {
    let base = rebuilt_rel(character, a, b, &[], h);
    let per: Vec<String> = GROUPS
        .iter()
        .map(|(name, swap)| {
            format!(
                "{name} {:.2}",
                100.0 * rebuilt_rel(character, a, b, swap, h)
            )
        })
        .collect();
    (
        base,
        format!("{:.2} % (none): {}", 100.0 * base, per.join(", ")),
    )
}

/// The torso joints' rotations in the two results apart, per axis of the
/// AMC result's body (mean signed degrees over the frames: about its
/// left-right axis, + the BVH's leaning further forward; about its
/// forward axis; about the vertical), printed.
fn torso_axes(a: &[(Pose, Rotations)], b: &[(Pose, Rotations)]) -> String {
    let mut out = Vec::new();
    for c in [C::Pelvis, C::Spine, C::Chest, C::Neck, C::Head] {
        let j = c.index();
        let mut sum = glam::DVec3::ZERO;
        for ((pa, qa), (_, qb)) in a.iter().zip(b) {
            let l = (pa[C::LHip.index()] - pa[C::RHip.index()])
                + (pa[C::LShoulder.index()] - pa[C::RShoulder.index()]);
            let left = glam::DVec3::new(l.x, 0.0, l.z).normalize_or_zero();
            let fwd = glam::DVec3::Y.cross(left);
            let mut d = qb[j] * qa[j].inverse();
            if d.w < 0.0 {
                d = -d;
            }
            let v = d.to_scaled_axis();
            sum += glam::DVec3::new(v.dot(left), v.dot(fwd), v.y);
        }
        let m = sum / a.len() as f64;
        out.push(format!(
            "{c:?} {:+.1}/{:+.1}/{:+.1}",
            m.x.to_degrees(),
            m.y.to_degrees(),
            m.z.to_degrees()
        ));
    }
    format!(
        "the torso's rotations apart (BVH against AMC, degrees about the left-right / forward / vertical axes) {}",
        out.join(", ")
    )
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn one_performance_as_amc_and_as_bvh_retargets_alike() {
    let Some(d) = common::data_dir() else { return };
    let m = d.join("mocap");
    let (character, h) = common::walk_character();
    // (AMC, BVH, abs limit, rel limit, pelvis limit): the figures reached
    // (see the module docs), with a margin of 0.1 % of the height.
    let pairs = [
        (
            "cmu-amc/01/01_01.amc",
            "cmu-bvh/01_01.bvh",
            0.001,
            0.001,
            0.001,
        ),
        (
            "cmu-amc/02/02_01.amc",
            "cmu-bvh-ccrig/002_01.bvh",
            0.019,
            0.0138,
            0.0224,
        ),
        (
            "cmu-amc/02/02_02.amc",
            "cmu-bvh-ccrig/002_02.bvh",
            0.0216,
            0.015,
            0.0252,
        ),
        (
            "cmu-amc/02/02_03.amc",
            "cmu-bvh-ccrig/002_03.bvh",
            0.022,
            0.017,
            0.0226,
        ),
        // The same conversion written again with every joint's rotation
        // channels in another order (X Y Z for the file's Z Y X): the same
        // rotations, so the same figures.
        ("cmu-amc/02/02_03.amc", REORDERED, 0.022, 0.017, 0.0226),
        // Turned 30° about the vertical and scaled by 1.37, the result
        // turned back: the same figures (asserted below to 1e-4 of the
        // height; the contact band is a fraction of the leg).
        ("cmu-amc/02/02_03.amc", TURNED, 0.022, 0.017, 0.0226),
        // Both files mirrored left for right: the same figures (asserted
        // below to 0.1 % of the height; the character is the generated
        // walk's, symmetric).
        ("cmu-amc/02/02_03.amc", MIRRORED, 0.022, 0.017, 0.0226),
        // Re-timed: the BVH resampled to 24 fps, then to the 30 fps every
        // clip is read at, so its frames are interpolated twice (a run at
        // 24 fps loses its footfalls' detail: 3.28 % apart, 1.84 % about
        // the pelvis, the pelvis 3.11 %, measured).
        ("cmu-amc/02/02_03.amc", RETIMED, 0.035, 0.021, 0.034),
    ];
    let mut got = Vec::new();
    let reordered = reordered_channels(&m.join("cmu-bvh-ccrig/002_03.bvh"));
    for (a, b, abs_max, rel_max, pelvis_max) in pairs {
        let mut amc = load_clip(&m.join(a), &Default::default()).unwrap();
        let b_path = if b == TURNED || b == RETIMED || b == MIRRORED {
            m.join("cmu-bvh-ccrig/002_03.bvh")
        } else if b == REORDERED {
            reordered.clone()
        } else {
            m.join(b)
        };
        let mut bvh = load_clip(&b_path, &Default::default()).unwrap();
        amc.to_metres_y_up();
        bvh.to_metres_y_up();
        if b == RETIMED {
            bvh = bvh.try_resampled(24.0).unwrap();
        }
        let (amc, bvh, gap) = aligned(&amc, &bvh);
        assert!(
            gap < 3.0,
            "{a} vs {b}: knees {gap:.2} degrees apart at best"
        );
        // The turned variant's result turned back about the character's
        // root (the kernel keeps the clip's heading of travel).
        let q = DQuat::from_rotation_y(30f64.to_radians());
        let c0 = character[C::Pelvis.index()] * glam::DVec3::new(1.0, 0.0, 1.0);
        let mirror = b == MIRRORED;
        let on = |c: &Clip, turn: bool| -> (Vec<(Pose, Rotations)>, f64, Vec<Pose>) {
            let c = c.try_resampled(30.0).unwrap();
            let map = detect_clip(&c).unwrap().map;
            let mut cp = clip_poses(&c, &map).unwrap();
            eprintln!("{a} vs {b}: reference {}", cp.reference.source);
            if turn {
                cp = turned(cp, q, 1.37);
            }
            if mirror {
                cp = mirrored(cp);
            }
            let out = retarget(&character, &cp.reference, &cp.poses)
                .into_iter()
                .map(|(p, g)| {
                    if turn {
                        (
                            p.map(|x| c0 + q.inverse() * (x - c0)),
                            g.map(|r| q.inverse() * r),
                        )
                    } else {
                        (p, g)
                    }
                })
                .collect();
            (out, leg_length(&cp.reference.pose), cp.poses)
        };
        let ((ga, la, pa), (gb, lb, pb)) = (on(&amc, false), on(&bvh, b == TURNED));
        let n = ga.len().min(gb.len());
        let (ra, rb): (Vec<Pose>, Vec<Pose>) = (
            ga.iter().map(|x| x.0).collect(),
            gb.iter().map(|x| x.0).collect(),
        );
        let (rel_fk, shares) = posture_shares(&character, &ga[..n], &gb[..n], h);
        let axes = torso_axes(&ga[..n], &gb[..n]);
        eprintln!(
            "{a} vs {b}: about the pelvis, given the AMC result's rotations of {shares}; {axes}"
        );
        let p = C::Pelvis.index();
        // The root's horizontal travel over the common span.
        let travel = |q: &[Pose]| {
            let d = q[n - 1][p] - q[0][p];
            d.x.hypot(d.z)
        };
        let (ta, tb) = (travel(&pa), travel(&pb));
        let (mut abs, mut rel, mut pelvis) = (0.0, 0.0, 0.0);
        for f in 0..n {
            pelvis += ra[f][p].distance(rb[f][p]);
            for c in Canonical::ALL {
                let j = c.index();
                abs += ra[f][j].distance(rb[f][j]);
                rel += (ra[f][j] - ra[f][p]).distance(rb[f][j] - rb[f][p]);
            }
        }
        // Where the gap is: per joint, the mean distance (abs, rel) over
        // the frames, % of the height; the pelvis split into horizontal
        // and vertical.
        let per_joint: Vec<String> = Canonical::ALL
            .iter()
            .map(|c| {
                let j = c.index();
                let (mut a, mut r) = (0.0, 0.0);
                for f in 0..n {
                    a += ra[f][j].distance(rb[f][j]);
                    r += (ra[f][j] - ra[f][p]).distance(rb[f][j] - rb[f][p]);
                }
                let k = 100.0 / n as f64 / h;
                format!("{c:?} {:.2}/{:.2}", a * k, r * k)
            })
            .collect();
        let (mut horizontal, mut vertical) = (0.0, 0.0);
        for f in 0..n {
            let d = ra[f][p] - rb[f][p];
            horizontal += d.x.hypot(d.z);
            vertical += d.y.abs();
        }
        eprintln!(
            "{a} vs {b}: per joint (abs/rel %) {}; the pelvis horizontal {:.2}, vertical {:.2}",
            per_joint.join(", "),
            100.0 * horizontal / n as f64 / h,
            100.0 * vertical / n as f64 / h
        );
        let (abs, rel) = (
            abs / (n * Canonical::COUNT) as f64 / h,
            rel / (n * Canonical::COUNT) as f64 / h,
        );
        let pelvis = pelvis / n as f64 / h;
        // The breakdown re-builds the BVH's result from its rotations: it
        // must give the measured posture back.
        assert!(
            (rel_fk - rel).abs() < 1e-9,
            "{a} vs {b}: {rel_fk} re-built against {rel}"
        );
        eprintln!(
            "{a} vs {b}: {n} frames at 30 fps, {:.2}% of the height apart, {:.2}% about the pelvis, \
             the pelvis {:.2}%; legs {:.4}, travel {:.4} times the AMC's",
            100.0 * abs,
            100.0 * rel,
            100.0 * pelvis,
            lb / la,
            tb / ta
        );
        got.push((
            a,
            b,
            abs,
            rel,
            pelvis,
            abs_max,
            rel_max,
            pelvis_max,
            lb / la,
            tb / ta,
            vertical / n as f64 / h,
        ));
    }
    // A clip turned and scaled retargets as the clip: the contact band
    // scales with the leg (with a fixed 3 cm band the pelvis stood 1.28 %
    // of the height from the AMC's vertically instead of 1.17 %).
    let of = |b: &str| got.iter().find(|g| g.1 == b).map(|g| [g.2, g.3, g.4, g.10]);
    let (Some(plain), Some(turned), Some(mirror)) =
        (of("cmu-bvh-ccrig/002_03.bvh"), of(TURNED), of(MIRRORED))
    else {
        panic!("the 02_03 pairs were not measured");
    };
    // Mirrored: the same figures within 0.1 % of the height (the kernel
    // has no side of its own).
    assert!(
        plain.iter().zip(&mirror).all(|(x, y)| (x - y).abs() < 1e-3),
        "mirrored (abs, rel, pelvis, its vertical): {mirror:?} against {plain:?}"
    );
    // Within 1e-4 of the height (the ground's levelling shrinks its slope
    // by a ridge in metres, which does not scale with the clip).
    assert!(
        plain.iter().zip(&turned).all(|(x, y)| (x - y).abs() < 1e-4),
        "turned and rescaled (abs, rel, pelvis, its vertical): {turned:?} against {plain:?}"
    );
    for (a, b, abs, rel, pelvis, abs_max, rel_max, pelvis_max, legs, travel, _) in got {
        assert!(
            abs < abs_max && rel < rel_max && pelvis < pelvis_max,
            "{a}: {abs} {rel} {pelvis}"
        );
        if a.contains("/02/") && b != TURNED {
            // The conversion's travel is not scaled by the legs.
            assert!(
                (legs - 1.164).abs() < 0.005 && (travel - 1.146).abs() < 0.006,
                "{a}: {legs} {travel}"
            );
        }
    }
}

/// The limb chains: each bone (from, to) joins two joints every rig puts
/// at the same anatomical joint, in order from the chain's root (the hip
/// or the shoulder).
const LIMB_CHAINS: [[(C, C); 3]; 2] = [
    [
        (C::LHip, C::LKnee),
        (C::LKnee, C::LAnkle),
        (C::LAnkle, C::LToe),
    ],
    [
        (C::RHip, C::RKnee),
        (C::RKnee, C::RAnkle),
        (C::RAnkle, C::RToe),
    ],
];
const ARM_CHAINS: [[(C, C); 2]; 2] = [
    [(C::LShoulder, C::LElbow), (C::LElbow, C::LWrist)],
    [(C::RShoulder, C::RElbow), (C::RElbow, C::RWrist)],
];

/// Every limb bone, legs then arms.
fn limb_bones() -> Vec<(C, C)> {
    let mut v: Vec<(C, C)> = LIMB_CHAINS.iter().flatten().copied().collect();
    v.extend(ARM_CHAINS.iter().flatten().copied());
    v
}

/// The body's heading frame of pose `p` (left, up, forward; from the
/// hips' and shoulders' lines), as a rotation taking body axes to world.
fn heading(p: &Pose) -> DQuat {
    let l = (p[C::LHip.index()] - p[C::RHip.index()])
        + (p[C::LShoulder.index()] - p[C::RShoulder.index()]);
    let left = glam::DVec3::new(l.x, 0.0, l.z).normalize_or_zero();
    let fwd = left.cross(glam::DVec3::Y);
    DQuat::from_mat3(&glam::DMat3::from_cols(left, glam::DVec3::Y, fwd))
}

/// The limb joints (knees, ankles, toes, elbows, wrists) about their
/// chain's root, built on `character`'s bone lengths from the bone
/// directions `dir(bone)`: what a retarget that copies limb directions
/// gives.
fn limbs_on(character: &Pose, dir: &dyn Fn(C, C) -> glam::DVec3) -> Vec<glam::DVec3> {
    let len = |a: C, b: C| character[a.index()].distance(character[b.index()]);
    let mut out = Vec::new();
    let mut chain = |bones: &[(C, C)]| {
        let mut at = glam::DVec3::ZERO;
        for &(a, b) in bones {
            at += len(a, b) * dir(a, b);
            out.push(at);
        }
    };
    for c in &LIMB_CHAINS {
        chain(c);
    }
    for c in &ARM_CHAINS {
        chain(c);
    }
    out
}

/// The limb joints of a result (or any pose) about their chain's root.
fn limbs_of(p: &Pose) -> Vec<glam::DVec3> {
    limb_bones()
        .iter()
        .map(|&(_, b)| {
            let root = match b {
                C::LKnee | C::LAnkle | C::LToe => C::LHip,
                C::RKnee | C::RAnkle | C::RToe => C::RHip,
                C::LElbow | C::LWrist => C::LShoulder,
                _ => C::RShoulder,
            };
            p[b.index()] - p[root.index()]
        })
        .collect()
}

/// Mean distance (over frames and the ten limb joints) between two lists
/// of limb joints per frame, over `h`.
fn limb_gap(a: &[Vec<glam::DVec3>], b: &[Vec<glam::DVec3>], h: f64) -> f64 {
    let n = a.len().min(b.len());
    let mut s = 0.0;
    for f in 0..n {
        for (x, y) in a[f].iter().zip(&b[f]) {
            s += x.distance(*y);
        }
    }
    s / (n * a[0].len()) as f64 / h
}

/// What the data leaves of the limbs' gap, whatever the kernel (issue 44:
/// "if the remaining gap is in the data, prove it"). Per pair of files
/// of one performance (aligned in time, both at 30 fps as `retarget`
/// reads them), the limb joints about their chain's root (hip or
/// shoulder) built on one character from each file's own bone
/// directions, no kernel involved:
/// - `world`: the directions as read, the BVH's turned by the one yaw
///   that fits the AMC's best: what any retarget copying the limbs'
///   directions must show;
/// - `varying`: each file's directions in its own body heading frame, and
///   each bone's mean offset between the files removed: the part no
///   reference, rest pose, bone placement or per-bone correction can
///   take away, since it changes frame by frame.
///
/// Against it, the kernel's results' limbs (the same measure on
/// `retarget`'s output), and the same with the BVH given the AMC's
/// levelling: the kernel levels each clip by its feet's ground
/// (`ground_tilt`), the conversion dropped the root's vertical channel and
/// with it the AMC floor's slope (CMU subject 02's: 0.8-1.0°, the
/// conversion's 0.1-0.2°), so the AMC's bones are turned by it and the
/// BVH's are not; and the other way round, the AMC's levelling undone
/// about each pelvis (its bones as captured, as the BVH's are).
///
/// Measured (session 31; 02_01 / 02_02 / 02_03, % of the height): the
/// limbs from the files' directions 0.73 / 0.78 / 0.98 as read, 0.32 /
/// 0.37 / 0.51 varying; the kernel's 1.09 / 1.11 / 1.53 (per joint on
/// 02_03, the files' / the kernel's: knees 1.10 / 1.62, ankles 1.29 /
/// 2.16, toes 2.17 / 3.20, elbows 0.19 / 0.25, wrists 0.14 / 0.41); each
/// result's thighs, shins and arms turned from its own clip's by 0.8-1.0°
/// (AMC) and 0.06-0.25° (BVH), its feet by 8-11° and 16-19°. Levelled
/// alike the limbs come to 0.67 / 0.70 / 1.17 (the BVH given the AMC's
/// tilt) or 0.68 / 0.69 / 1.12 (the AMC's undone), but the whole does not:
/// 1.81 / 2.07 / 2.12 → 1.86 / 2.14 / 2.25 or 1.87 / 2.14 / 2.17 %, about
/// the pelvis 1.28 / 1.40 / 1.59 → 1.26 / 1.39 / 1.61 or 1.26 / 1.40 /
/// 1.59 (01_01's own pair moves 0.10-0.14 % either way: its floor's 0.22°).
/// The root's travel per leg, BVH / AMC, 0.983 / 0.984 / 0.986. Also the root's travel per leg length, the
/// data's: the two files' pelvises must drift apart by that ratio under
/// any rule that scales the travel by a bone length. Checked: the same
/// capture in the same skeleton (01_01, AMC and cgspeed BVH) has no
/// floor; the floor never exceeds the kernel's gap by more than 10 %
/// (the kernel smooths, so it may fall a little under); the mirrored
/// 02_03 pair has the plain pair's floor.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_limbs_gap_between_two_files_is_in_the_data() {
    let Some(d) = common::data_dir() else { return };
    let m = d.join("mocap");
    let (character, h) = common::walk_character();
    let mut got = Vec::new();
    let mut got_slopes = Vec::new();
    for (a, b, mirror) in [
        ("cmu-amc/01/01_01.amc", "cmu-bvh/01_01.bvh", false),
        ("cmu-amc/02/02_01.amc", "cmu-bvh-ccrig/002_01.bvh", false),
        ("cmu-amc/02/02_02.amc", "cmu-bvh-ccrig/002_02.bvh", false),
        ("cmu-amc/02/02_03.amc", "cmu-bvh-ccrig/002_03.bvh", false),
        ("cmu-amc/02/02_03.amc", "cmu-bvh-ccrig/002_03.bvh", true),
    ] {
        let f = two_files(&m, a, b);
        let read = |c: &Clip| {
            let cp = poses_at_30(c);
            if mirror { mirrored(cp) } else { cp }
        };
        let (ca, cb) = (read(&f.al), read(&f.bl));
        let n = ca.poses.len().min(cb.poses.len());
        let (pa, pb) = (&ca.poses[..n], &cb.poses[..n]);
        let dir = |p: &Pose, x: C, y: C| (p[y.index()] - p[x.index()]).normalize();
        // World: one yaw for the whole clip, the best of a 0.05° scan.
        let bones = limb_bones();
        let yaw = best_yaw(pa, pb, &bones, 400);
        let q = DQuat::from_rotation_y(yaw.to_radians());
        let la: Vec<_> = (0..n)
            .map(|f| limbs_on(&character, &|x, y| dir(&pa[f], x, y)))
            .collect();
        let lb: Vec<_> = (0..n)
            .map(|f| limbs_on(&character, &|x, y| q * dir(&pb[f], x, y)))
            .collect();
        let world = limb_gap(&la, &lb, h);
        // Varying: in each file's heading frame, each bone's mean offset
        // (the arc between the mean directions) removed from the BVH's.
        let local = |p: &Pose, x: C, y: C| heading(p).inverse() * dir(p, x, y);
        let offset: Vec<DQuat> = bones
            .iter()
            .map(|&(x, y)| {
                let (mut sa, mut sb) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
                for f in 0..n {
                    sa += local(&pa[f], x, y);
                    sb += local(&pb[f], x, y);
                }
                DQuat::from_rotation_arc(sb.normalize(), sa.normalize())
            })
            .collect();
        let at = |x: C, y: C| bones.iter().position(|&b| b == (x, y)).unwrap();
        let va: Vec<_> = (0..n)
            .map(|f| limbs_on(&character, &|x, y| local(&pa[f], x, y)))
            .collect();
        let vb: Vec<_> = (0..n)
            .map(|f| limbs_on(&character, &|x, y| offset[at(x, y)] * local(&pb[f], x, y)))
            .collect();
        let varying = limb_gap(&va, &vb, h);
        // The kernel's results, the same measure.
        let on = |cp: &ClipPoses| -> Vec<Vec<glam::DVec3>> {
            retarget(&character, &cp.reference, &cp.poses)
                .into_iter()
                .map(|(p, _)| limbs_of(&p))
                .collect()
        };
        let kernel = limb_gap(&on(&ca), &on(&cb), h);
        // Per joint: the floor (as read) against the kernel's gap; and per
        // bone, how far each file's result turns from its own clip's
        // direction (mean degrees; the bone's direction in the result
        // against the clip's, world).
        let (ka, kb) = (on(&ca), on(&cb));
        let names = ["knee", "ankle", "toe", "elbow", "wrist"];
        let slot = |i: usize| match i {
            0 | 3 => 0,
            1 | 4 => 1,
            2 | 5 => 2,
            6 | 8 => 3,
            _ => 4,
        };
        let (mut fj, mut kj) = ([0.0f64; 5], [0.0f64; 5]);
        for f in 0..n {
            for i in 0..10 {
                fj[slot(i)] += la[f][i].distance(lb[f][i]);
                kj[slot(i)] += ka[f][i].distance(kb[f][i]);
            }
        }
        let per_joint: Vec<String> = (0..5)
            .map(|k| {
                let u = 100.0 / (2 * n) as f64 / h;
                format!("{} {:.2}/{:.2}", names[k], fj[k] * u, kj[k] * u)
            })
            .collect();
        let turned_from_clip = |cp: &ClipPoses| -> String {
            let res: Vec<Pose> = retarget(&character, &cp.reference, &cp.poses)
                .into_iter()
                .map(|(p, _)| p)
                .collect();
            let groups = ["thigh", "shin", "foot", "upper arm", "forearm"];
            let mut sum = [0.0f64; 5];
            for (f, r) in res.iter().enumerate() {
                for (i, &(x, y)) in bones.iter().enumerate() {
                    let g = [0, 1, 2, 0, 1, 2, 3, 4, 3, 4][i];
                    sum[g] += dir(r, x, y)
                        .angle_between(dir(&cp.poses[f], x, y))
                        .to_degrees();
                }
            }
            (0..5)
                .map(|g| format!("{} {:.2}", groups[g], sum[g] / (2 * n) as f64))
                .collect::<Vec<_>>()
                .join(", ")
        };
        eprintln!(
            "{a} vs {b}{}: per joint (the files' directions / the kernel's, %) {};              each result's bones off its own clip's (mean degrees): AMC {}; BVH {}",
            if mirror { " (mirrored)" } else { "" },
            per_joint.join(", "),
            turned_from_clip(&ca),
            turned_from_clip(&cb)
        );
        // The floor's slope: the kernel levels each clip by its feet's
        // ground (`ground_tilt`); the conversion dropped the root's
        // vertical channel, and the AMC's floor slope with it. The BVH
        // given the AMC's levelling (each pose, its reference and file
        // rotations turned about its pelvis by the AMC's tilt: its floor
        // stays level, its bones lean as the AMC's are levelled to).
        let tilt = |cp: &ClipPoses| ground_tilt(&cp.poses).to_axis_angle().1.to_degrees();
        let cbt = about_pelvis(cb.clone(), ground_tilt(&ca.poses));
        // The other way: the AMC's poses and file rotations turned about
        // each pelvis by the inverse of its tilt (its rest reference kept),
        // so that the kernel's levelling, still read off its sloping floor,
        // leaves its bones as captured, as the BVH's are.
        let cat = about_pelvis(ca.clone(), ground_tilt(&ca.poses).inverse());
        let (ga, gb, gbt) = (
            results(&character, &ca),
            results(&character, &cb),
            results(&character, &cbt),
        );
        let (abs, rel) = apart_abs_rel(&ga, &gb, h);
        let limbs = |r: &[Pose]| -> Vec<Vec<glam::DVec3>> { r.iter().map(limbs_of).collect() };
        let (abs_t, rel_t) = apart_abs_rel(&ga, &gbt, h);
        let gat = results(&character, &cat);
        let (abs_u, rel_u) = apart_abs_rel(&gat, &gb, h);
        let kernel_u = limb_gap(&limbs(&gat), &limbs(&gb), h);
        eprintln!(
            "{a} vs {b}{}: the AMC's bones left as captured (its levelling undone about each pelvis): \
             {:.2} % apart, {:.2} % about the pelvis, limbs {:.2}",
            if mirror { " (mirrored)" } else { "" },
            100.0 * abs_u,
            100.0 * rel_u,
            100.0 * kernel_u
        );
        let kernel_t = limb_gap(&limbs(&ga), &limbs(&gbt), h);
        eprintln!(
            "{a} vs {b}{}: the floors' slopes (ground_tilt) AMC {:.2}°, BVH {:.2}°; \
             the kernel's results {:.2} % apart, {:.2} % about the pelvis, limbs {:.2}; \
             the BVH given the AMC's levelling {:.2}, {:.2}, limbs {:.2}",
            if mirror { " (mirrored)" } else { "" },
            tilt(&ca),
            tilt(&cb),
            100.0 * abs,
            100.0 * rel,
            100.0 * kernel,
            100.0 * abs_t,
            100.0 * rel_t,
            100.0 * kernel_t
        );
        // The root's travel per leg, the data's.
        let p = C::Pelvis.index();
        let travel = |q: &[Pose]| {
            let d = q[n - 1][p] - q[0][p];
            d.x.hypot(d.z)
        };
        let per_leg = (travel(pb) / leg_length(&cb.reference.pose))
            / (travel(pa) / leg_length(&ca.reference.pose));
        got_slopes.push((a, tilt(&ca), tilt(&cb), kernel, kernel_t.max(kernel_u)));
        eprintln!(
            "{a} vs {b}{}: the limbs about their hip or shoulder, % of the height: \
             from the files' directions (no kernel) {:.2} as read (one yaw, {yaw:+.2}°), \
             {:.2} varying frame by frame; the kernel's results {:.2}; \
             the root's travel per leg, BVH / AMC {per_leg:.4}",
            if mirror { " (mirrored)" } else { "" },
            100.0 * world,
            100.0 * varying,
            100.0 * kernel
        );
        got.push((a, b, mirror, world, varying, kernel, per_leg));
    }
    for &(a, b, _, world, varying, kernel, per_leg) in &got {
        if a.contains("01_01") {
            assert!(
                world < 2e-4 && varying < 2e-4 && kernel < 2e-4,
                "{a} vs {b}: {world} {varying} {kernel}"
            );
            assert!((per_leg - 1.0).abs() < 1e-3, "{a} vs {b}: {per_leg}");
            continue;
        }
        assert!(varying <= world + 1e-4, "{a} vs {b}: {varying} > {world}");
        assert!(
            world < 1.1 * kernel,
            "{a} vs {b}: the floor {world} over the kernel's {kernel}"
        );
        // The conversion's travel is 1.6 % short of its legs.
        assert!((per_leg - 0.984).abs() < 0.006, "{a} vs {b}: {per_leg}");
    }
    // The conversions' floors are level (their roots' vertical channel
    // dropped), the AMCs' are not; levelled alike (either way round), the
    // kernel's limbs come nearer by at least 0.2 % of the height.
    for &(a, ta, tb, kernel, kernel_t) in &got_slopes {
        if a.contains("/02/") {
            assert!(ta > 0.5 && tb < 0.25, "{a}: slopes {ta} {tb}");
            assert!(kernel_t < kernel - 0.002, "{a}: {kernel_t} {kernel}");
        }
    }
    let plain = got.iter().find(|g| g.1.contains("002_03") && !g.2).unwrap();
    let mirror = got.iter().find(|g| g.2).unwrap();
    for (x, y) in [
        (plain.3, mirror.3),
        (plain.4, mirror.4),
        (plain.5, mirror.5),
    ] {
        assert!((x - y).abs() < 1e-3, "mirrored {y} against {x}");
    }
}

/// `cp` with each pose turned by `q` about its own pelvis (so the root's
/// path and the floor stay where they were), a frame reference's pose the
/// same way (a rest skeleton's is kept) and the file joints' world
/// rotations by `q`.
fn about_pelvis(mut cp: ClipPoses, q: DQuat) -> ClipPoses {
    let p = C::Pelvis.index();
    let frame = matches!(
        cp.reference.source,
        surfmotion::pose::retarget::ClipNeutralSource::Frame(_)
    );
    let reference = frame.then_some(&mut cp.reference.pose);
    for x in cp.poses.iter_mut().chain(reference) {
        let o = x[p];
        *x = x.map(|v| o + q * (v - o));
    }
    let rotations: Vec<_> = cp
        .reference
        .rotations
        .iter()
        .map(|w| w.map(|r| r.map(|r| q * r)))
        .collect();
    cp.reference.rotations = rotations.into();
    cp
}

/// The kernel's results (joint positions per frame) of `cp` on `character`.
fn results(character: &Pose, cp: &ClipPoses) -> Vec<Pose> {
    retarget(character, &cp.reference, &cp.poses)
        .into_iter()
        .map(|(p, _)| p)
        .collect()
}

/// Mean distance over frames and joints between two results (abs), and
/// about their pelvises (rel), over `h`.
fn apart_abs_rel(a: &[Pose], b: &[Pose], h: f64) -> (f64, f64) {
    let n = a.len().min(b.len());
    let p = C::Pelvis.index();
    let (mut abs, mut rel) = (0.0, 0.0);
    for f in 0..n {
        for c in Canonical::ALL {
            let j = c.index();
            abs += a[f][j].distance(b[f][j]);
            rel += (a[f][j] - a[f][p]).distance(b[f][j] - b[f][p]);
        }
    }
    let k = (n * Canonical::COUNT) as f64 * h;
    (abs / k, rel / k)
}

/// The yaw (degrees; a 0.05° scan over ±`steps`·0.05°) that turns `pb`'s
/// bone directions onto `pa`'s best over the frames both have.
pub(super) fn best_yaw(pa: &[Pose], pb: &[Pose], bones: &[(C, C)], steps: i32) -> f64 {
    let dir = |p: &Pose, x: C, y: C| (p[y.index()] - p[x.index()]).normalize_or_zero();
    let n = pa.len().min(pb.len());
    let cost = |yaw: f64| -> f64 {
        let q = DQuat::from_rotation_y(yaw.to_radians());
        (0..n)
            .map(|f| {
                bones
                    .iter()
                    .map(|&(x, y)| (q * dir(&pb[f], x, y)).distance_squared(dir(&pa[f], x, y)))
                    .sum::<f64>()
            })
            .sum()
    };
    (-steps..=steps)
        .map(|k| {
            let yaw = f64::from(k) * 0.05;
            (yaw, cost(yaw))
        })
        .min_by(|u, v| u.1.total_cmp(&v.1))
        .map_or(0.0, |(yaw, _)| yaw)
}
