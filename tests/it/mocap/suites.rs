//! BVH skeletons of more mocap suites, game-engine rigs and research
//! datasets (issue 17), each written as a compact skeleton description
//! learnt from public sources (named in each one's comment), with the
//! quirks of its files: a root node above the pelvis, six channels on
//! several joints, channel orders other than ZXY, CRLF line ends and tabs,
//! Z-up, mm/cm/m, T-, A- and psi-pose rests, helper, twist, prop and end
//! joints with channels, zero-length single-axis chains, a clavicle named
//! "shoulder".
//!
//! Each is checked as `mocap rigmap` and `inspect` read it (full canonical
//! map with no rig map, the convention named right or "unknown
//! convention, mapped by …", left/right from geometry also when mirrored,
//! unit and up axis), and the project's procedural walk is written onto
//! each skeleton (bone by bone, through its own rest) and retargeted onto
//! the procedural character as `retarget` reads a clip: the result must be
//! the walk the original skeleton gives, standing and walking forward.
//! Non-humanoids are refused with "not a humanoid: …" and exit 1.

use crate::common;

use common::skel::{Skel, Suite, expected, map_errors, mirror, parse_skel, swap_side};

use glam::{DQuat, DVec3};
use surfmotion::mocap::bvh::{BvhOptions, format_bvh, parse_bvh};
use surfmotion::mocap::{Clip, PointConvention};
use surfmotion::pose::Pose;
use surfmotion::rig::{BY_NAMES, BY_STRUCTURE, Canonical, RigError, detect_clip, load_clip};
use surfmotion::synth::clips::{Gait, gait_clip};

// ------------------------------------------------------------ the skeletons

const BY_N: &str = BY_NAMES;
const BY_S: &str = BY_STRUCTURE;

const SUITES: &[Suite] = &[
    Suite {
        name: "deepmotion",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=hips_JNT;spine=spine_JNT;chest=spine2_JNT;neck=neck_JNT;head=head_JNT;\
              l_shoulder=l_arm_JNT;l_elbow=l_forearm_JNT;l_wrist=l_hand_JNT;\
              r_shoulder=r_arm_JNT;r_elbow=r_forearm_JNT;r_wrist=r_hand_JNT;\
              l_hip=l_upleg_JNT;l_knee=l_leg_JNT;l_ankle=l_foot_JNT;l_toe=l_toebase_JNT;\
              r_hip=r_upleg_JNT;r_knee=r_leg_JNT;r_ankle=r_foot_JNT;r_toe=r_toebase_JNT",
        skel: "
# DeepMotion Animate 3D BVH: `_JNT` suffixes, hips_JNT, spine_JNT,
# spine1_JNT, spine2_JNT, neck_JNT, head_JNT, l_shoulder_JNT (the
# clavicle: the upper arm is l_arm_JNT), l_forearm_JNT, l_hand_JNT,
# l_handIndex1_JNT.. fingers, l_upleg_JNT, l_leg_JNT, l_foot_JNT,
# l_toebase_JNT. Names and tree from a public Blender rigging script's
# _bones_deepmotion() template (\"52 bones, DeepMotion naming _JNT\") and a
# motion-stream spec listing hips_JNT as root, T-pose, metres, Y-up; this
# file in cm.
unit cm
axes y
order Zrotation Xrotation Yrotation
hips_JNT 0 100 0
 l_upleg_JNT 9 -5 0
  l_leg_JNT 0 -44 1
   l_foot_JNT 0 -42 -2
    l_toebase_JNT 0 -7 13 | 0 0 7
 mirror l_upleg_JNT l_=>r_
 spine_JNT 0 10 -1
  spine1_JNT 0 12 0
   spine2_JNT 0 13 0
    neck_JNT 0 16 1
     head_JNT 0 10 2 | 0 18 0
    l_shoulder_JNT 3 12 0
     l_arm_JNT 13 0 0
      l_forearm_JNT 27 0 0
       l_hand_JNT 25 0 0
        l_handIndex1_JNT 9 0 2
         l_handIndex2_JNT 4 0 0
          l_handIndex3_JNT 3 0 0 | 2 0 0
        l_handThumb1_JNT 3 -1 3
         l_handThumb2_JNT 3 0 2
          l_handThumb3_JNT 2 0 1 | 2 0 1
    mirror l_shoulder_JNT l_=>r_
",
    },
    Suite {
        name: "genea_talking_with_hands",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=b_root;spine=b_spine0;chest=b_spine3;neck=b_neck0;head=b_head;\
              l_shoulder=b_l_arm;l_elbow=b_l_forearm;l_wrist=b_l_wrist;\
              r_shoulder=b_r_arm;r_elbow=b_r_forearm;r_wrist=b_r_wrist;\
              l_hip=b_l_upleg;l_knee=b_l_leg;l_ankle=b_l_foot;l_toe=~;\
              r_hip=b_r_upleg;r_knee=b_r_leg;r_ankle=b_r_foot;r_toe=~",
        skel: "
# GENEA 2022 challenge (Talking With Hands 16.2M) BVH: body_world at the
# origin above b_root (both translating), b_l_upleg, b_l_leg,
# b_l_foot_twist, b_l_foot, b_spine0..3, b_neck0, b_head, b_l_shoulder (the
# clavicle) carrying the prop p_l_scap and b_l_arm, b_l_arm_twist,
# b_l_forearm, b_l_wrist_twist, b_l_wrist, fingers b_l_index1.., the prop
# p_navel; right side first. Joint list and parents from public GENEA
# processing scripts (target_joints, corps_name_GENEA_2022, a PARENTS
# table). cm, Y-up, facing +Z, T-pose; X Y Z rotation order.
unit cm
axes y
order Xrotation Yrotation Zrotation
body_world 0 0 0
 b_root 0 98 0 % 6
  b_r_upleg -10 -4 0
   b_r_leg 0 -43 0
    b_r_foot_twist 0 -43 0
     b_r_foot 0 0 0 | 0 -6 14
  mirror b_r_upleg r_=>l_
  b_spine0 0 8 0
   p_navel 0 2 11 | 0 0 2
   b_spine1 0 10 0
    b_spine2 0 10 0
     b_spine3 0 10 0
      b_neck0 0 14 0
       b_head 0 10 2 | 0 17 0
      b_r_shoulder -3 10 0
       p_r_scap -4 -4 -7 | 0 -8 0
       b_r_arm -14 0 0
        b_r_arm_twist -14 0 0
         b_r_forearm -14 0 0
          b_r_wrist_twist -13 0 0
           b_r_wrist -13 0 0
            b_r_index1 -9 0 2
             b_r_index2 -4 0 0 | -3 0 0
            b_r_thumb0 -2 -1 2
             b_r_thumb1 -3 0 2 | -2 0 1
      mirror b_r_shoulder r_=>l_
",
    },
    Suite {
        name: "beat_zeggs",
        convention: "MotionBuilder HumanIK",
        sides: "from names, confirmed by geometry",
        map: "pelvis=Hips;spine=Spine;chest=Spine3;neck=Neck;head=Head;\
              l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
              r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
              l_hip=LeftUpLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=LeftToeBase;\
              r_hip=RightUpLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=RightToeBase",
        skel: "
# BEAT (and ZEGGS) gesture datasets: 75 joints, Hips, Spine..Spine3, Neck,
# Neck1, Head, HeadEnd (a joint with channels), RightShoulder, RightArm,
# RightForeArm, RightHand, RightHandMiddle1..4 and other fingers,
# RightUpLeg, RightLeg, RightFoot, RightForeFoot (mid-foot, between the
# ankle and the toes), RightToeBase, RightToeBaseEnd (a joint); right side
# first. Names and kinematic tree from a public BEAT loader (BEAT_JOINTS,
# BEAT_75_KINTREE, NAME_MAPPER). cm, Y-up, facing +Z, T-pose; CRLF.
unit cm
axes y
order Yrotation Xrotation Zrotation
crlf
Hips 0 95 0
 Spine 0 9 -1
  Spine1 0 9 0
   Spine2 0 9 0
    Spine3 0 9 0
     Neck 0 15 1
      Neck1 0 5 0
       Head 0 6 1
        HeadEnd 0 17 0 | 0 1 0
     RightShoulder -3 11 0
      RightArm -13 0 0
       RightForeArm -27 0 0
        RightHand -25 0 0
         RightHandMiddle1 -9 0 0
          RightHandMiddle2 -4 0 0
           RightHandMiddle3 -3 0 0
            RightHandMiddle4 -2 0 0 | -1 0 0
         RightHandThumb1 -3 -1 3
          RightHandThumb2 -3 0 2
           RightHandThumb3 -2 0 1
            RightHandThumb4 -2 0 1 | -1 0 0
     mirror RightShoulder Right=>Left
 RightUpLeg -9 -4 0
  RightLeg 0 -42 0
   RightFoot 0 -42 -1
    RightForeFoot 0 -5 8
     RightToeBase 0 -3 6
      RightToeBaseEnd 0 0 5 | 0 0 1
 mirror RightUpLeg Right=>Left
",
    },
    Suite {
        name: "smpl_fbx_unity",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=m_avg_Pelvis;spine=m_avg_Spine1;chest=m_avg_Spine3;neck=m_avg_Neck;\
              head=m_avg_Head;l_shoulder=m_avg_L_Shoulder;l_elbow=m_avg_L_Elbow;\
              l_wrist=m_avg_L_Wrist;r_shoulder=m_avg_R_Shoulder;r_elbow=m_avg_R_Elbow;\
              r_wrist=m_avg_R_Wrist;l_hip=m_avg_L_Hip;l_knee=m_avg_L_Knee;\
              l_ankle=m_avg_L_Ankle;l_toe=m_avg_L_Foot;r_hip=m_avg_R_Hip;\
              r_knee=m_avg_R_Knee;r_ankle=m_avg_R_Ankle;r_toe=m_avg_R_Foot",
        skel: "
# SMPL's FBX/Unity model exported to BVH (VIBE, ROMP, 4DHumans, EDGE and
# AIST++ tools write it): every joint prefixed `m_avg_`, an m_avg_root node
# at the origin above m_avg_Pelvis (both translating), m_avg_L_Collar,
# m_avg_L_Shoulder (the upper arm), m_avg_L_Hand. Names from public
# SMPL-to-FBX scripts (SmplObjects.joints, JOINT_NAMES); rest offsets
# from a public UNITY_OFFSETS table (x negated: right-handed). m, Y-up,
# facing +Z, T-pose; tabs.
unit m
axes y
order Zrotation Yrotation Xrotation
tabs
m_avg_root 0 0 0
 m_avg_Pelvis 0.0022 0.9726 0.0286 % 6
  m_avg_L_Hip 0.0586 -0.0823 -0.0177
   m_avg_L_Knee 0.0435 -0.3865 0.0081
    m_avg_L_Ankle -0.0148 -0.4269 -0.0374
     m_avg_L_Foot 0.0411 -0.0603 0.1220 | 0 0 0.05
  m_avg_R_Hip -0.0603 -0.0905 -0.0135
   m_avg_R_Knee -0.0433 -0.3837 -0.0048
    m_avg_R_Ankle 0.0191 -0.4200 -0.0346
     m_avg_R_Foot -0.0348 -0.0621 0.1303 | 0 0 0.05
  m_avg_Spine1 -0.0044 0.1244 -0.0384
   m_avg_Spine2 0.0045 0.1380 0.0268
    m_avg_Spine3 -0.0023 0.0560 0.0029
     m_avg_Neck -0.0134 0.2116 -0.0335
      m_avg_Head 0.0101 0.0889 0.0504 | 0 0.15 0
     m_avg_L_Collar 0.0717 0.1140 -0.0189
      m_avg_L_Shoulder 0.1229 0.0452 -0.0190
       m_avg_L_Elbow 0.2553 -0.0156 -0.0229
        m_avg_L_Wrist 0.2657 0.0127 -0.0073
         m_avg_L_Hand 0.0867 -0.0106 -0.0156 | 0.06 0 0
     m_avg_R_Collar -0.0830 0.1125 -0.0237
      m_avg_R_Shoulder -0.1132 0.0468 -0.0085
       m_avg_R_Elbow -0.2601 -0.0143 -0.0313
        m_avg_R_Wrist -0.2691 0.0068 -0.0060
         m_avg_R_Hand -0.0888 -0.0087 -0.0102 | -0.06 0 0
",
    },
    Suite {
        name: "hdm05_asf_names",
        convention: "CMU ASF/AMC",
        sides: "from names, confirmed by geometry",
        map: "pelvis=root;spine=upperback;chest=thorax;neck=lowerneck;head=head;\
              l_shoulder=lhumerus;l_elbow=lradius;l_wrist=lwrist;\
              r_shoulder=rhumerus;r_elbow=rradius;r_wrist=rwrist;\
              l_hip=lfemur;l_knee=ltibia;l_ankle=lfoot;l_toe=ltoes;\
              r_hip=rfemur;r_knee=rtibia;r_ankle=rfoot;r_toe=rtoes",
        skel: "
# HDM05 (Müller et al. 2007) and other ASF/AMC collections converted to
# BVH with the ASF bone names kept: each BVH joint is an ASF bone, placed
# at the end of its parent bone (root, lhipjoint, lfemur at the hip,
# ltibia, lfoot, ltoes; lowerback, upperback, thorax, lowerneck,
# upperneck, head; lclavicle, lhumerus, lradius, lwrist, lhand, lfingers,
# lthumb). Bone names from the HDM05/CMU ASF skeleton (public ASF files
# and parsers). Arms down at 45 degrees (the ASF's axis-aligned arms bent
# down as converters write them); inches, Y-up, facing +Z.
unit inch
axes y
scale 0.3937
order Zrotation Yrotation Xrotation
root 0 96 0
 lhipjoint 0 0 0
  lfemur 9 -8 2
   ltibia 0 -42 0
    lfoot 0 -41 0
     ltoes 0 -3 13 | 0 0 5
 rhipjoint 0 0 0
  rfemur -9 -8 2
   rtibia 0 -42 0
    rfoot 0 -41 0
     rtoes 0 -3 13 | 0 0 5
 lowerback 0 0 0
  upperback 0 12 -1
   thorax 0 12 0
    lowerneck 0 13 0
     upperneck 0 8 1
      head 0 7 1 | 0 17 0
    lclavicle 0 13 0
     lhumerus 17 3 0
      lradius 20 -20 0
       lwrist 18 -18 0
        lhand 2 -2 0
         lfingers 4 -4 0 | 3 -3 0
        lthumb 1 -2 2 | 2 -2 2
    rclavicle 0 13 0
     rhumerus -17 3 0
      rradius -20 -20 0
       rwrist -18 -18 0
        rhand -2 -2 0
         rfingers -4 -4 0 | -3 -3 0
        rthumb -1 -2 2 | -2 -2 2
",
    },
    Suite {
        name: "kit_mmm",
        convention: BY_S,
        sides: "from geometry",
        map: "pelvis=BPx_joint|BPy_joint|BPz_joint;spine=BTx_joint|BTy_joint|BTz_joint;\
              chest=~;neck=BLNx_joint|BLNy_joint|BLNz_joint;\
              head=BUNx_joint|BUNy_joint|BUNz_joint;\
              l_shoulder=LSx_joint|LSy_joint|LSz_joint;l_elbow=LEx_joint|LEz_joint;\
              l_wrist=LWx_joint|LWy_joint;\
              r_shoulder=RSx_joint|RSy_joint|RSz_joint;r_elbow=REx_joint|REz_joint;\
              r_wrist=RWx_joint|RWy_joint;\
              l_hip=LHx_joint|LHy_joint|LHz_joint;l_knee=LKx_joint;\
              l_ankle=LAx_joint|LAy_joint|LAz_joint;l_toe=LFx_joint;\
              r_hip=RHx_joint|RHy_joint|RHz_joint;r_knee=RKx_joint;\
              r_ankle=RAx_joint|RAy_joint|RAz_joint;r_toe=RFx_joint",
        skel: "
# KIT Whole-Body Human Motion Database, MMM reference model, as a BVH that
# writes each single-axis MMM joint as its own BVH joint: chains of
# zero-length joints (BPx, BPy, BPz pelvis; BTx.. torso; BLNx.. lower neck;
# BUNx.. upper neck; LSx, LSy, LSz shoulder; LEx, LEz elbow; LWx, LWy
# wrist; LHx.. hip; LKx knee; LAx.. ankle; LFx foot). Joint names from
# public KIT-ML/MMM loaders (joint_names: BLNx_joint, BPx_joint, ...,
# LMrot_joint). Names carry no usable words: structure decides. Arms down;
# mm, Z-up, facing +Y (left at -X).
unit mm
axes zup+y
scale 10
order Xrotation Yrotation Zrotation
BPx_joint 0 95 0
 BPy_joint 0 0 0
  BPz_joint 0 0 0
   LHx_joint 9 -6 0
    LHy_joint 0 0 0
     LHz_joint 0 0 0
      LKx_joint 0 -42 0
       LAx_joint 0 -42 0
        LAy_joint 0 0 0
         LAz_joint 0 0 0
          LFx_joint 0 -4 12 | 0 0 6
   mirror LHx_joint L=>R
   BTx_joint 0 12 0
    BTy_joint 0 0 0
     BTz_joint 0 0 0
      BLNx_joint 0 36 0
       BLNy_joint 0 0 0
        BLNz_joint 0 0 0
         BUNx_joint 0 10 1
          BUNy_joint 0 0 0
           BUNz_joint 0 0 0 | 0 21 0
      LSx_joint 18 31 0
       LSy_joint 0 0 0
        LSz_joint 0 0 0
         LEx_joint 0 -29 0
          LEz_joint 0 0 0
           LWx_joint 0 -26 0
            LWy_joint 0 0 0 | 0 -9 0
      mirror LSx_joint L=>R
",
    },
    Suite {
        name: "motionbuilder_reference",
        convention: "MotionBuilder HumanIK",
        sides: "from names, confirmed by geometry",
        map: "pelvis=Hips;spine=Spine;chest=Spine2;neck=Neck;head=Head;\
              l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
              r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
              l_hip=LeftUpLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=LeftToeBase;\
              r_hip=RightUpLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=RightToeBase",
        skel: "
# MotionBuilder (HumanIK) BVH export of a characterised skeleton: a
# ClipNeutral node at the origin above Hips (both with position channels),
# HumanIK names with the roll helpers (LeftUpLegRoll, LeftLegRoll,
# LeftArmRoll, LeftForeArmRoll) as leaves beside the limb bones,
# LeftFootExtraFinger1, LeftHandThumb1.., HeadEnd. Names from the HumanIK
# bone list (public HumanIK mapping tables: LeftUpLegRoll, LeftForeArmRoll,
# ClipNeutral). cm, Y-up, facing +Z, T-pose; X Y Z rotation order; CRLF.
unit cm
axes y
order Xrotation Yrotation Zrotation
crlf
ClipNeutral 0 0 0
 Hips 0 99 0 % 6
  LeftUpLeg 9 -4 0
   LeftUpLegRoll 0 -21 0 | 0 -5 0
   LeftLeg 0 -43 0
    LeftLegRoll 0 -21 0 | 0 -5 0
    LeftFoot 0 -43 -1
     LeftToeBase 0 -7 13
      LeftFootExtraFinger1 0 0 5 | 0 0 2
  mirror LeftUpLeg Left=>Right
  Spine 0 10 -1
   Spine1 0 12 0
    Spine2 0 12 0
     Neck 0 16 1
      Head 0 10 2
       HeadEnd 0 18 0 | 0 1 0
     LeftShoulder 3 12 0
      LeftArm 13 0 0
       LeftArmRoll 14 0 0 | 4 0 0
       LeftForeArm 27 0 0
        LeftForeArmRoll 13 0 0 | 4 0 0
        LeftHand 25 0 0
         LeftHandThumb1 3 -1 3
          LeftHandThumb2 3 0 2 | 2 0 1
         LeftHandIndex1 9 0 2
          LeftHandIndex2 4 0 0 | 3 0 0
     mirror LeftShoulder Left=>Right
",
    },
    Suite {
        name: "unity_humanoid",
        convention: "Unity Humanoid",
        sides: "from names, confirmed by geometry",
        map: "pelvis=Hips;spine=Spine;chest=UpperChest;neck=Neck;head=Head;\
              l_shoulder=LeftUpperArm;l_elbow=LeftLowerArm;l_wrist=LeftHand;\
              r_shoulder=RightUpperArm;r_elbow=RightLowerArm;r_wrist=RightHand;\
              l_hip=LeftUpperLeg;l_knee=LeftLowerLeg;l_ankle=LeftFoot;l_toe=LeftToes;\
              r_hip=RightUpperLeg;r_knee=RightLowerLeg;r_ankle=RightFoot;r_toe=RightToes",
        skel: "
# A Unity Humanoid avatar recorded to BVH (Unity BVH recorders name the
# bones by HumanBodyBones): Hips, Spine, Chest, UpperChest, Neck, Head,
# LeftEye, RightEye, Jaw, LeftShoulder, LeftUpperArm, LeftLowerArm,
# LeftHand, LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToes. Names from
# Unity's HumanBodyBones enumeration (public docs). m, Y-up, facing +Z,
# A-pose (arms 40 degrees below horizontal); tabs.
unit m
axes y
order Zrotation Xrotation Yrotation
tabs
Hips 0 0.97 0
 LeftUpperLeg 0.09 -0.05 0
  LeftLowerLeg 0 -0.43 0.01
   LeftFoot 0 -0.42 -0.02
    LeftToes 0 -0.06 0.13 | 0 0 0.06
 mirror LeftUpperLeg Left=>Right
 Spine 0 0.09 0
  Chest 0 0.12 0
   UpperChest 0 0.13 0
    Neck 0 0.15 0.01
     Head 0 0.09 0.02 | 0 0.18 0
      LeftEye 0.03 0.07 0.08 | 0 0 0.02
      RightEye -0.03 0.07 0.08 | 0 0 0.02
      Jaw 0 -0.01 0.04 | 0 -0.03 0.06
    LeftShoulder 0.03 0.11 0
     LeftUpperArm 0.12 0 0
      LeftLowerArm 0.207 -0.174 0
       LeftHand 0.192 -0.161 0 | 0.07 -0.06 0
    mirror LeftShoulder Left=>Right
",
    },
    Suite {
        name: "mixamo_split_san",
        convention: "MotionBuilder HumanIK",
        sides: "from names, confirmed by geometry",
        map: "pelvis=Hips;spine=Spine;chest=Spine2;neck=Neck;head=Head;\
              l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
              r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
              l_hip=LeftUpLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=LeftToeBase;\
              r_hip=RightUpLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=RightToeBase",
        skel: "
# Mixamo characters as the skeleton-aware networks' data set writes them
# (deep-motion-editing, 'mixamo2_m'): no `mixamorig:` prefix, helper joints
# `Spine1_split` and `LeftShoulder_split` splitting bones in two, end
# joints with channels (`LeftToe_End`, `HeadTop_End`). Joint list from a
# public SAN BVH_file class (corps_name_mixamo2_m). cm, Y-up, facing +Z,
# T-pose; six channels on every joint.
unit cm
axes y
order Zrotation Yrotation Xrotation
all6
Hips 0 104 0
 LeftUpLeg 9 -7 0
  LeftLeg 0 -45 0
   LeftFoot 0 -44 -2
    LeftToeBase 0 -7 13
     LeftToe_End 0 0 8 | 0 0 1
 mirror LeftUpLeg Left=>Right
 Spine 0 10 0
  Spine1 0 6 0
   Spine1_split 0 6 0
    Spine2 0 13 0
     Neck 0 16 1
      Head 0 10 2
       HeadTop_End 0 19 0 | 0 1 0
     LeftShoulder 3 12 0
      LeftShoulder_split 6 0 0
       LeftArm 7 0 0
        LeftForeArm 27 0 0
         LeftHand 25 0 0 | 8 0 0
     mirror LeftShoulder Left=>Right
",
    },
    Suite {
        name: "kinect_openni",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=Torso;spine=~;chest=~;neck=Neck;head=Head;\
              l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftHand;\
              r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightHand;\
              l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftFoot;l_toe=~;\
              r_hip=RightHip;r_knee=RightKnee;r_ankle=RightFoot;r_toe=~",
        skel: "
# Kinect v1 through OpenNI/NiTE written as BVH: the 15 tracked joints
# (XnSkeletonJoint: TORSO, NECK, HEAD, LEFT_SHOULDER, LEFT_ELBOW,
# LEFT_HAND, LEFT_HIP, LEFT_KNEE, LEFT_FOOT, ...), the root the torso
# centre with the neck, both shoulders and both hips off it: no pelvis
# joint, no spine, no toes; 'Hand' is the wrist and 'Foot' the ankle. Rest
# in the calibration 'psi' pose (upper arms out, forearms up). mm, Y-up,
# the person facing the camera (-Z, left at -X).
unit mm
axes y-z
scale 10
order Zrotation Xrotation Yrotation
Torso 0 112 0
 Neck 0 34 0
  Head 0 16 1 | 0 15 0
 LeftShoulder 17 31 0
  LeftElbow 28 0 0
   LeftHand 0 26 0 | 0 9 0
 mirror LeftShoulder Left=>Right
 LeftHip 9 -22 0
  LeftKnee 0 -44 1
   LeftFoot 0 -43 -2 | 0 -4 12
 mirror LeftHip Left=>Right
",
    },
    Suite {
        name: "qualisys_qtm",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=Hips;spine=Waist;chest=Chest;neck=Neck;head=Head;\
              l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftWrist;\
              r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightWrist;\
              l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftAnkle;l_toe=LeftFoot;\
              r_hip=RightHip;r_knee=RightKnee;r_ankle=RightAnkle;r_toe=RightFoot",
        skel: "
# Qualisys Track Manager's skeleton solver (segments Hips, Waist, Chest,
# LeftCollar, LeftShoulder = the upper arm, LeftElbow = the forearm,
# LeftWrist, Neck, Head, LeftHip = the thigh, LeftKnee, LeftAnkle,
# LeftFoot = the forefoot), as its BVH export names them. Segment names,
# parents and positions from the skeleton XML example of Qualisys's public
# real-time protocol documentation (lab frame: Z-up, the subject facing
# -Y). mm, Z-up, facing -Y; the neck off the chest 30 cm above it.
unit mm
axes zup-y
scale 10
order Zrotation Xrotation Yrotation
Hips 0 99 0
 Waist 0 12 0
  Chest 0 12 -1
   LeftCollar 5 25 1
    LeftShoulder 13 -4 2
     LeftElbow 26 1 0
      LeftWrist 25 -5 0 | 8 0 0
   mirror LeftCollar Left=>Right
   Neck 0 30 -2
    Head 0 9 3 | 0 18 0
 LeftHip 9 -2 -5
  LeftKnee 1 -43 0
   LeftAnkle 0 -46 -1
    LeftFoot 0 -7 12 | 0 0 5
 mirror LeftHip Left=>Right
",
    },
    Suite {
        name: "mmd_japanese",
        convention: BY_S,
        sides: "from geometry",
        map: "pelvis=腰|下半身;spine=上半身;chest=上半身2;neck=首;head=頭;\
              l_shoulder=左腕;l_elbow=左ひじ;l_wrist=左手首;\
              r_shoulder=右腕;r_elbow=右ひじ;r_wrist=右手首;\
              l_hip=左足;l_knee=左ひざ;l_ankle=左足首;l_toe=左つま先;\
              r_hip=右足;r_knee=右ひざ;r_ankle=右足首;r_toe=右つま先",
        skel: "
# MikuMikuDance (PMX) standard bones as VMD/PMX-to-BVH converters write
# them, in Japanese: 全ての親 (all parents) at the floor, センター (centre),
# グルーブ, 腰 (waist) carrying 上半身 (upper body) → 上半身2 → 首 → 頭 and
# 下半身 (lower body, a short bone down) carrying the legs 左足 → 左ひざ →
# 左足首 → 左つま先; arms 左肩P → 左肩 (clavicle) → 左腕 → 左腕捩 (twist) →
# 左ひじ → 左手捩 → 左手首, thumb 左親指０..; eyes 左目; leg IK chains
# 左足ＩＫ親 → 左足ＩＫ → 左つま先ＩＫ (full-width letters) under 全ての親;
# skirt chains (スカート前, スカート後, スカート左, ...: no word the names
# know) off 下半身 beside the legs, as many PMX models carry.
# Bone names and parents from public VMD standard-bone tables and MMD bone
# reference charts. MMD units (8 cm); Y-up, facing -Z; A-pose.
# No name is an ASCII word: structure decides, sides from geometry.
unit mmd
axes y-z
scale 0.125
order Zrotation Xrotation Yrotation
全ての親 0 0 0
 センター 0 88 0 % 6
  グルーブ 0 2 0
   腰 0 6 0
    上半身 0 2 0
     上半身2 0 12 0
      首 0 22 0
       頭 0 8 1 | 0 16 0
        左目 3 6 7 | 0 0 1
        右目 -3 6 7 | 0 0 1
      左肩P 3 20 0
       左肩 0 0 0
        左腕 12 0 0
         左腕捩 10 -9 0
          左ひじ 10 -9 0
           左手捩 9 -8 0
            左手首 9 -8 0
             左親指０ 2 -3 2
              左親指１ 2 -2 1 | 1 -1 1
      mirror 左肩P 左=>右
    下半身 0 -1 0
     スカート前 0 -2 9
      スカート前2 0 -16 3 | 0 -14 2
     スカート後 0 -2 -9
      スカート後2 0 -16 -3 | 0 -14 -2
     スカート左 11 -2 0
      スカート左2 4 -16 0 | 2 -14 0
     mirror スカート左 左=>右
     左足 9 -8 0
      左ひざ 0 -42 1
       左足首 0 -42 -2
        左つま先 0 -7 12 | 0 0 2
     mirror 左足 左=>右
 左足ＩＫ親 9 0 -2
  左足ＩＫ 0 8 0
   左つま先ＩＫ 0 -8 12 | 0 0 2
 mirror 左足ＩＫ親 左=>右
",
    },
    Suite {
        name: "mmd_english",
        convention: BY_S,
        sides: "from geometry",
        map: "pelvis=waist|lower body;spine=upper body;chest=upper body2;neck=neck;head=head;\
              l_shoulder=arm_L;l_elbow=elbow_L;l_wrist=wrist_L;\
              r_shoulder=arm_R;r_elbow=elbow_R;r_wrist=wrist_R;\
              l_hip=leg_L;l_knee=knee_L;l_ankle=ankle_L;l_toe=toe_L;\
              r_hip=leg_R;r_knee=knee_R;r_ankle=ankle_R;r_toe=toe_R",
        skel: "
# The same MMD skeleton with the semi-standard English bone names (spaces
# inside names: `upper body`, `lower body`, `arm twist_L`, `leg IK_L`;
# `leg_L` is the thigh, `arm_L` the upper arm, `shoulder_L` the clavicle).
# Names from public MMD bone translation tables. Written in cm, tabs, CRLF.
unit cm
axes y-z
order Zrotation Xrotation Yrotation
tabs
crlf
all parents 0 0 0
 center 0 88 0 % 6
  groove 0 2 0
   waist 0 6 0
    upper body 0 2 0
     upper body2 0 12 0
      neck 0 22 0
       head 0 8 1 | 0 16 0
        eye_L 3 6 7 | 0 0 1
        eye_R -3 6 7 | 0 0 1
      shoulderP_L 3 20 0
       shoulder_L 0 0 0
        arm_L 12 0 0
         arm twist_L 10 -9 0
          elbow_L 10 -9 0
           wrist twist_L 9 -8 0
            wrist_L 9 -8 0 | 3 -3 0
      mirror shoulderP_L _L=>_R
    lower body 0 -1 0
     leg_L 9 -8 0
      knee_L 0 -42 1
       ankle_L 0 -42 -2
        toe_L 0 -7 12 | 0 0 2
     mirror leg_L _L=>_R
 leg IKP_L 9 0 -2
  leg IK_L 0 8 0
   toe IK_L 0 -8 12 | 0 0 2
 mirror leg IKP_L _L=>_R
",
    },
    Suite {
        name: "makehuman",
        convention: BY_S,
        sides: "from geometry",
        map: "pelvis=root;spine=spine04|spine03;chest=spine01;neck=neck01;head=head;\
              l_shoulder=shoulder01.L|upperarm01.L;l_elbow=lowerarm01.L;l_wrist=wrist.L;\
              r_shoulder=shoulder01.R|upperarm01.R;r_elbow=lowerarm01.R;r_wrist=wrist.R;\
              l_hip=upperleg01.L;l_knee=lowerleg01.L;l_ankle=foot.L;l_toe=toe1-1.L;\
              r_hip=upperleg01.R;r_knee=lowerleg01.R;r_ankle=foot.R;r_toe=toe1-1.R",
        skel: "
# MakeHuman's default skeleton exported to BVH: root → spine05..spine01,
# neck01..neck03, head; clavicle.L → shoulder01.L → upperarm01.L →
# upperarm02.L (the upper arm in two twist halves) → lowerarm01.L →
# lowerarm02.L → wrist.L; root → pelvis.L (the hip bone) → upperleg01.L →
# upperleg02.L → lowerleg01.L → lowerleg02.L → foot.L → toe1-1.L. Bone
# names from MakeHuman's public skeleton files and its BVH exporter and
# retarget tables. dm (MakeHuman's unit), Y-up, facing +Z, A-pose arms.
unit dm
scale 0.1
order Zrotation Xrotation Yrotation
root 0 100 -1
 spine05 0 3 -1
  spine04 0 7 0
   spine03 0 8 0
    spine02 0 9 0
     spine01 0 9 0
      neck01 0 8 0
       neck02 0 4 0
        neck03 0 4 1
         head 0 3 1 | 0 17 0
      clavicle.L 2 6 2
       shoulder01.L 13 0 -3
        upperarm01.L 3 -2 0
         upperarm02.L 10 -8 0
          lowerarm01.L 10 -9 0
           lowerarm02.L 10 -9 0
            wrist.L 10 -8 0 | 6 -5 0
      mirror clavicle.L .L=>.R
 pelvis.L 2 -1 0
  upperleg01.L 7 -4 0
   upperleg02.L 0 -21 0
    lowerleg01.L 0 -22 0
     lowerleg02.L 0 -21 0
      foot.L 0 -21 0
       toe1-1.L 0 -6 12 | 0 0 3
 mirror pelvis.L .L=>.R
",
    },
    Suite {
        name: "vroid_tail_skirt",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=J_Bip_C_Hips;spine=J_Bip_C_Spine;chest=J_Bip_C_UpperChest;neck=J_Bip_C_Neck;\
              head=J_Bip_C_Head;l_shoulder=J_Bip_L_UpperArm;l_elbow=J_Bip_L_LowerArm;\
              l_wrist=J_Bip_L_Hand;r_shoulder=J_Bip_R_UpperArm;r_elbow=J_Bip_R_LowerArm;\
              r_wrist=J_Bip_R_Hand;l_hip=J_Bip_L_UpperLeg;l_knee=J_Bip_L_LowerLeg;\
              l_ankle=J_Bip_L_Foot;l_toe=J_Bip_L_ToeBase;r_hip=J_Bip_R_UpperLeg;\
              r_knee=J_Bip_R_LowerLeg;r_ankle=J_Bip_R_Foot;r_toe=J_Bip_R_ToeBase",
        skel: "
# A VRoid character in a skirt with a tail (VRoid Studio's skirt and
# accessory springs: J_Sec_L_SkirtFront_01.., J_Sec_L_SkirtSide_01..,
# J_Sec_L_SkirtBack_01.., a J_Sec_Tail chain, long J_Sec_Hair chains from
# the head down the back), all off the hips beside the legs: nine chains
# meet at J_Bip_C_Hips. Bone names from VRoid's public bone lists (J_Bip_*,
# J_Sec_*). m, Y-up, facing +Z, T-pose.
unit m
scale 0.01
order Zrotation Xrotation Yrotation
J_Bip_C_Hips 0 95 0
 J_Sec_Tail_01 0 -2 -8
  J_Sec_Tail_02 0 -15 -5
   J_Sec_Tail_03 0 -20 -3
    J_Sec_Tail_04 0 -20 -2 | 0 -15 0
 J_Sec_L_SkirtFront_01 6 -2 8
  J_Sec_L_SkirtFront_02 2 -15 2 | 1 -15 1
 J_Sec_L_SkirtBack_01 6 -2 -8
  J_Sec_L_SkirtBack_02 2 -15 -2 | 1 -15 -1
 J_Sec_L_SkirtSide_01 12 -2 0
  J_Sec_L_SkirtSide_02 4 -15 0 | 2 -15 0
 mirror J_Sec_L_SkirtFront_01 _L_=>_R_
 mirror J_Sec_L_SkirtBack_01 _L_=>_R_
 mirror J_Sec_L_SkirtSide_01 _L_=>_R_
 J_Bip_L_UpperLeg 9 -5 0
  J_Bip_L_LowerLeg 0 -42 0
   J_Bip_L_Foot 0 -42 0
    J_Bip_L_ToeBase 0 -6 12 | 0 0 4
 mirror J_Bip_L_UpperLeg _L_=>_R_
 J_Bip_C_Spine 0 10 0
  J_Bip_C_Chest 0 12 0
   J_Bip_C_UpperChest 0 12 0
    J_Bip_C_Neck 0 15 0
     J_Bip_C_Head 0 10 1 | 0 18 0
      J_Sec_Hair1_01 0 10 -10
       J_Sec_Hair1_02 0 -25 -3
        J_Sec_Hair1_03 0 -25 -2
         J_Sec_Hair1_04 0 -25 -1 | 0 -20 0
    J_Bip_L_Shoulder 3 12 0
     J_Bip_L_UpperArm 10 0 0
      J_Bip_L_LowerArm 26 0 0
       J_Bip_L_Hand 25 0 0 | 8 0 0
    mirror J_Bip_L_Shoulder _L_=>_R_
",
    },
    Suite {
        name: "unreal_cape",
        convention: "Unreal Engine mannequin",
        sides: "from names, confirmed by geometry",
        map: "pelvis=pelvis;spine=spine_01|spine_02;chest=spine_03;neck=neck_01;head=head;\
              l_shoulder=upperarm_l;l_elbow=lowerarm_l;l_wrist=hand_l;\
              r_shoulder=upperarm_r;r_elbow=lowerarm_r;r_wrist=hand_r;\
              l_hip=thigh_l;l_knee=calf_l;l_ankle=foot_l;l_toe=ball_l;\
              r_hip=thigh_r;r_knee=calf_r;r_ankle=foot_r;r_toe=ball_r",
        skel: "
# An Unreal (UE4 mannequin names) game character with a cape: cloth
# chains cape_l_01.., cape_m_01.., cape_r_01.. hanging from spine_03 down
# the back beside the clavicles and the neck (six chains off the chest
# node). UE4 bone names from public retarget tables (pelvis,
# spine_01..03, clavicle_l, upperarm_l, lowerarm_l, hand_l, thigh_l,
# calf_l, foot_l, ball_l); the cloth chains as game rigs name them. cm,
# Y-up, facing +Z, T-pose.
unit cm
order Zrotation Xrotation Yrotation
pelvis 0 95 0
 thigh_l 9 -5 0
  calf_l 0 -43 0
   foot_l 0 -42 0
    ball_l 0 -6 12 | 0 0 4
 mirror thigh_l _l=>_r
 spine_01 0 10 0
  spine_02 0 12 0
   spine_03 0 12 0
    neck_01 0 15 0
     head 0 10 1 | 0 17 0
    cape_l_01 8 10 -10
     cape_l_02 1 -25 -3
      cape_l_03 1 -25 -2
       cape_l_04 1 -25 -2 | 0 -20 0
    cape_m_01 0 10 -10
     cape_m_02 0 -25 -3
      cape_m_03 0 -25 -2
       cape_m_04 0 -25 -2 | 0 -20 0
    mirror cape_l_01 _l_=>_r_
    clavicle_l 3 12 0
     upperarm_l 10 0 0
      lowerarm_l 26 0 0
       hand_l 25 0 0 | 8 0 0
    mirror clavicle_l _l=>_r
",
    },
    Suite {
        name: "threed_pose_tracker",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=Hip|Waist;spine=Chest;chest=UpperChest;neck=Neck;head=Head;\
              l_shoulder=LeftUpperArm;l_elbow=LeftLowerArm;l_wrist=LeftHand;\
              r_shoulder=RightUpperArm;r_elbow=RightLowerArm;r_wrist=RightHand;\
              l_hip=LeftUpperLeg;l_knee=LeftLowerLeg;l_ankle=LeftFoot;l_toe=LeftToes;\
              r_hip=RightUpperLeg;r_knee=RightLowerLeg;r_ankle=RightFoot;r_toe=RightToes",
        skel: "
# Pose-estimation-to-VRM BVH (ThreeDPoseTracker-style exporters): ROOT Hip
# with a zero-length Waist, Chest, UpperChest, LeftShoulder (clavicle),
# LeftUpperArm, LeftLowerArm, LeftHand, LeftUpperLeg.. LeftToes off Hip.
# Names and offsets (metres, the left arm at -X) from BVH headers stored in
# public repositories (ROOT Hip / CenterHip → Waist → Chest → UpperChest).
# m, Y-up, facing -Z.
unit m
axes y-z
scale 0.01
order Zrotation Xrotation Yrotation
Hip 0 95 0
 Waist 0 0 0
  Chest 0 20 0
   UpperChest 0 12 0
    LeftShoulder 3 12 0
     LeftUpperArm 10 2 0
      LeftLowerArm 26 0 0
       LeftHand 25 0 0 | 8 0 0
    mirror LeftShoulder Left=>Right
    Neck 0 15 0
     Head 0 10 1 | 0 15 0
 LeftUpperLeg 9 -5 0
  LeftLowerLeg 0 -42 0
   LeftFoot 0 -42 0
    LeftToes 0 -6 12 | 0 0 4
 mirror LeftUpperLeg Left=>Right
",
    },
    Suite {
        name: "winged_unnamed",
        convention: BY_N,
        sides: "from geometry",
        map: "pelvis=Hips;spine=Spine;chest=Spine2;neck=Neck;head=Head;\
              l_shoulder=LeftUpperArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
              r_shoulder=RightUpperArm;r_elbow=RightForeArm;r_wrist=RightHand;\
              l_hip=LeftUpperLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=LeftToeBase;\
              r_hip=RightUpperLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=RightToeBase",
        skel: "
# A winged game character (angel, dragon-man): wing chains LeftPinion1..4
# off the upper chest beside the clavicles, spreading back, out and up,
# longer than the legs; a cape chain Drape1..4 hanging down the back and a
# Dangle1..4 chain off the chest's front (a necklace or a tabard), a
# Sway1..4 tail off the hips, and three short Claw chains on each hand:
# seven chains off Spine2, none named as a helper or as a wing. Written
# after the wings and cloth of public game rigs (Unity humanoid names for
# the body). cm, Y-up, facing +Z, T-pose.
unit cm
order Zrotation Xrotation Yrotation
Hips 0 95 0
 LeftUpperLeg 9 -5 0
  LeftLeg 0 -43 0
   LeftFoot 0 -42 0
    LeftToeBase 0 -6 12 | 0 0 4
 mirror LeftUpperLeg Left=>Right
 Sway1 0 -3 -9
  Sway2 0 -20 -12
   Sway3 0 -20 -10
    Sway4 0 -18 -8 | 0 -12 -5
 Spine 0 10 0
  Spine1 0 12 0
   Spine2 0 12 0
    Neck 0 15 0
     Head 0 10 1 | 0 17 0
    LeftPinion1 6 8 -10
     LeftPinion2 20 20 -15
      LeftPinion3 30 10 -10
       LeftPinion4 30 -10 -5 | 20 -10 0
    mirror LeftPinion1 Left=>Right
    Drape1 0 8 -12
     Drape2 0 -25 -4
      Drape3 0 -25 -3
       Drape4 0 -25 -2 | 0 -20 0
    Dangle1 0 6 10
     Dangle2 0 -15 3
      Dangle3 0 -15 1 | 0 -10 0
    LeftShoulder 3 12 0
     LeftUpperArm 10 0 0
      LeftForeArm 26 0 0
       LeftHand 25 0 0
        LeftClawA 8 0 3 | 4 0 1
        LeftClawB 8 0 0 | 4 0 0
        LeftClawC 8 0 -3 | 4 0 -1
    mirror LeftShoulder Left=>Right
",
    },
    Suite {
        name: "winged_anonymous",
        convention: BY_S,
        sides: "from geometry",
        map: "pelvis=b00;spine=b10;chest=b12;neck=b13;head=b14;\
              l_shoulder=b31;l_elbow=b32;l_wrist=b33;\
              r_shoulder=b41;r_elbow=b42;r_wrist=b43;\
              l_hip=b01;l_knee=b02;l_ankle=b03;l_toe=b04;\
              r_hip=b05;r_knee=b06;r_ankle=b07;r_toe=b08",
        skel: "
# The winged character with every name replaced by a number (an exporter
# that writes bone indices), the wings shorter (as long as the legs) and
# off the chest's back, in an A-pose, children in another order (wings
# and cape before the neck and arms, the right side first), in mm, Y-up,
# facing -Z: structure alone decides.
unit mm
axes y-z
scale 10
order Zrotation Xrotation Yrotation
b00 0 95 0
 b10 0 10 0
  b11 0 12 0
   b12 0 12 0
    b50 0 8 -12
     b51 0 -25 -4
      b52 0 -25 -3 | 0 -20 0
    b25 -6 8 -10
     b26 -15 15 -12
      b27 -25 8 -8
       b28 -25 -8 -4 | -15 -8 0
    b20 6 8 -10
     b21 15 15 -12
      b22 25 8 -8
       b23 25 -8 -4 | 15 -8 0
    b40 -3 12 0
     b41 -10 0 0
      b42 -18 -18 0
       b43 -18 -18 0 | -6 -6 0
    b13 0 15 0
     b14 0 10 1 | 0 17 0
    b30 3 12 0
     b31 10 0 0
      b32 18 -18 0
       b33 18 -18 0 | 6 -6 0
 b05 -9 -5 0
  b06 0 -43 0
   b07 0 -42 0
    b08 0 -6 12 | 0 0 4
 b01 9 -5 0
  b02 0 -43 0
   b03 0 -42 0
    b04 0 -6 12 | 0 0 4
",
    },
];

/// Non-humanoids: a rope hanging from a humanoid-named root, a spider
/// with Left/Right legs, a table (four legs straight down, no spine).
const NOT_HUMANOIDS: &[(&str, &str)] = &[
    (
        "rope",
        "
# A single chain (a rope or a tail rig), named as a spine: no legs, no arms.
unit cm
Hips 0 150 0
 Spine 0 -12 0
  Spine1 0 -12 0
   Spine2 0 -12 0
    Spine3 0 -12 0
     Neck 0 -12 0
      Head 0 -12 0 | 0 -12 0
",
    ),
    (
        "spider",
        "
# A spider: eight legs off a body (LeftLeg1..4, RightLeg1..4), an abdomen.
unit cm
Body 0 20 0
 LeftLeg1 4 0 6
  LeftKnee1 14 10 14
   LeftFoot1 10 -30 10 | 2 -2 2
 LeftLeg2 5 0 2
  LeftKnee2 18 10 6
   LeftFoot2 14 -30 4 | 2 -2 0
 LeftLeg3 5 0 -2
  LeftKnee3 18 10 -6
   LeftFoot3 14 -30 -4 | 2 -2 0
 LeftLeg4 4 0 -6
  LeftKnee4 14 10 -14
   LeftFoot4 10 -30 -10 | 2 -2 -2
 RightLeg1 -4 0 6
  RightKnee1 -14 10 14
   RightFoot1 -10 -30 10 | -2 -2 2
 RightLeg2 -5 0 2
  RightKnee2 -18 10 6
   RightFoot2 -14 -30 4 | -2 -2 0
 RightLeg3 -5 0 -2
  RightKnee3 -18 10 -6
   RightFoot3 -14 -30 -4 | -2 -2 0
 RightLeg4 -4 0 -6
  RightKnee4 -14 10 -14
   RightFoot4 -10 -30 -10 | -2 -2 -2
 Abdomen 0 2 -10 | 0 0 -20
",
    ),
    (
        "trex_humanik_names",
        "
# A Truebones-style T-rex carrying every HumanIK name: body horizontal,
# tiny arms (too short to count as limbs), a long tail off the hips beside
# the legs, the neck forward. Names decide nothing for a horizontal body.
unit cm
Hips 0 300 0
 Spine 0 10 50
  Spine1 0 10 80
   Neck 0 20 80
    Head 0 20 60 | 0 0 80
   LeftArm 30 -20 30
    LeftForeArm 0 -30 20
     LeftHand 0 -20 10 | 0 -5 5
   mirror LeftArm Left=>Right
 Tail 0 0 -80
  Tail1 0 -10 -120
   Tail2 0 -10 -150
    Tail3 0 -10 -150 | 0 -5 -100
 LeftUpLeg 40 -20 0
  LeftLeg 0 -130 -20
   LeftFoot 0 -140 -30
    LeftToeBase 0 -10 50 | 0 0 20
 mirror LeftUpLeg Left=>Right
",
    ),
    (
        "legs_only",
        "
# A gait-lab lower-body model: pelvis, femurs, tibias, feet; no trunk.
unit mm
scale 10
Pelvis 0 95 0
 LFemur 9 -5 0
  LTibia 0 -43 0
   LFoot 0 -42 0
    LToes 0 -6 12 | 0 0 4
 mirror LFemur L=>R
",
    ),
    (
        "upper_body_only",
        "
# An upper-body gesture rig (no legs): Hips, spine, neck, head, arms down.
unit cm
Hips 0 95 0
 Spine 0 10 0
  Spine1 0 12 0
   Spine2 0 12 0
    Neck 0 15 0
     Head 0 10 1 | 0 17 0
    LeftShoulder 3 12 0
     LeftArm 10 0 0
      LeftForeArm 0 -26 0
       LeftHand 0 -25 0 | 0 -8 0
    mirror LeftShoulder Left=>Right
",
    ),
    (
        "crab",
        "
# A crab: a flat body, eight walking legs and two claws splayed around it,
# eye stalks; no names the rig words know.
unit cm
Carapace 0 20 0
 Leg1a 10 0 8
  Leg1b 15 5 5
   Leg1c 10 -25 3 | 2 -5 0
 Leg2a 12 0 3
  Leg2b 16 5 2
   Leg2c 10 -25 1 | 2 -5 0
 Leg3a 12 0 -3
  Leg3b 16 5 -2
   Leg3c 10 -25 -1 | 2 -5 0
 Leg4a 10 0 -8
  Leg4b 15 5 -5
   Leg4c 10 -25 -3 | 2 -5 0
 Pincer1 8 2 12
  Pincer2 10 5 12
   Pincer3 5 0 10 | 0 0 6
 mirror Leg1a Leg=>Gel
 mirror Leg2a Leg=>Gel
 mirror Leg3a Leg=>Gel
 mirror Leg4a Leg=>Gel
 mirror Pincer1 Pincer=>Nipper
 Stalk1 2 5 12 | 0 3 0
 mirror Stalk1 Stalk=>Klats
",
    ),
    (
        "winged_quadruped",
        "
# A griffin: four legs, wings off the withers, a neck and head forward, a
# tail; HumanIK names on the body, the wings unnamed. Horizontal.
unit cm
Hips 0 110 0
 LeftUpLeg 12 -10 0
  LeftLeg 0 -45 5
   LeftFoot 0 -45 -5
    LeftToeBase 0 -8 10 | 0 0 5
 mirror LeftUpLeg Left=>Right
 Tail 0 5 -15
  Tail1 0 -5 -30
   Tail2 0 -5 -30 | 0 -5 -20
 Spine 0 5 30
  Spine1 0 3 30
   Spine2 0 2 30
    Neck 0 25 20
     Head 0 15 15 | 0 0 25
    LeftShoulder 10 -5 5
     LeftArm 3 -20 5
      LeftForeArm 0 -40 0
       LeftHand 0 -40 0 | 0 -5 10
    mirror LeftShoulder Left=>Right
    LeftPinion1 8 12 -5
     LeftPinion2 30 25 -10
      LeftPinion3 40 10 -10
       LeftPinion4 35 -10 -5 | 20 -10 0
    mirror LeftPinion1 Left=>Right
",
    ),
    (
        "table",
        "
# A table rig: a top and four legs straight down (two named left, two right).
unit cm
Top 0 75 0
 LeftFrontLeg 50 0 30
  LeftFrontFoot 0 -75 0 | 0 -1 0
 RightFrontLeg -50 0 30
  RightFrontFoot 0 -75 0 | 0 -1 0
 LeftBackLeg 50 0 -30
  LeftBackFoot 0 -75 0 | 0 -1 0
 RightBackLeg -50 0 -30
  RightBackFoot 0 -75 0 | 0 -1 0
",
    ),
];

/// A description of `tests/fixtures/suites` (the families of
/// `tests/rig_mapping.rs`): offsets in the file's frame, the unit and the
/// frame as its comment states them (`cm, Z-up, facing -Y`). `None` for a
/// rest given by rotations (LAFAN1's `@`).
fn fixture_skel(text: &str) -> Option<Skel> {
    if text.lines().any(|l| !l.starts_with('#') && l.contains('@')) {
        return None;
    }
    let mut k = parse_skel(text);
    k.raw = true;
    let comment: String = text
        .lines()
        .filter(|l| l.starts_with('#'))
        .collect::<Vec<_>>()
        .join(" ");
    let words: Vec<&str> = comment
        .split_whitespace()
        .map(|w| w.trim_end_matches([',', '.', ';']))
        .collect();
    k.unit = words
        .iter()
        .rev()
        .find_map(|w| match *w {
            "mm" | "cm" | "m" => Some(w.to_string()),
            "inches" | "inch" => Some("inch".to_string()),
            _ => None,
        })
        .expect("a unit in the comment");
    k.axes = if comment.contains("Z-up, facing -Y") {
        "zup-y"
    } else if comment.contains("Z-up, facing +Y") {
        "zup+y"
    } else if comment.contains("(-Z") {
        "y-z"
    } else {
        "y"
    }
    .to_string();
    Some(k)
}

// ---------------------------------------------------------------- helpers

/// The clip as a BVH file reads back (through the project's reader).
fn via_text(s: &Skel, c: &Clip, name: &str) -> Clip {
    let text = s.text(c);
    parse_bvh(
        &text,
        std::path::Path::new(&format!("{name}.bvh")),
        &BvhOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A map to expect: per canonical joint, the accepted joint names (none:
/// derived).
type Want = Vec<(Canonical, Vec<String>)>;

// ------------------------------------------------------------ the mapping

/// A known convention must be named exactly; a family that is none may be
/// reported as mapped by names or by structure (never as a known one).
fn convention_ok(want: &str, got: &str) -> bool {
    if want == BY_N || want == BY_S {
        got == BY_N || got == BY_S
    } else {
        got == want
    }
}

/// Every family maps with no rig map to the full canonical map, names the
/// convention it should (a known one only when it is one), and says where
/// left and right came from. Every family is checked before failing.
#[test]
fn more_suites_map_every_canonical_joint() {
    let mut fails = Vec::new();
    for s in SUITES {
        let k = parse_skel(s.skel);
        let c = via_text(&k, &k.clip(), s.name);
        let d = match detect_clip(&c) {
            Ok(d) => d,
            Err(e) => {
                fails.push(format!("{}: {e}", s.name));
                continue;
            }
        };
        if !convention_ok(s.convention, &d.map.convention) {
            fails.push(format!("{}: convention '{}'", s.name, d.map.convention));
        }
        if !d.sides.starts_with(s.sides) {
            fails.push(format!("{}: sides {}", s.name, d.sides));
        }
        for e in map_errors(&d, &expected(s)) {
            fails.push(format!("{}: {e}", s.name));
        }
        // A derived chest sits halfway up spine→neck in every pose (it was
        // placed before the neck: halfway to the world origin).
        if d.map.derived.contains_key(&Canonical::Chest) {
            let moved = walk_onto(&k, &c, &expected(s), &gait_clip(Gait::Walk, 0.5, 30.0));
            for (f, p) in d.map.poses(&moved).unwrap().iter().enumerate() {
                let at = |c: Canonical| p[c.index()];
                let mid = 0.5 * (at(Canonical::Spine) + at(Canonical::Neck));
                if at(Canonical::Chest).distance(mid) > 1e-9 * mid.length().max(1.0) {
                    fails.push(format!(
                        "{}: derived chest off spine-neck in frame {f}",
                        s.name
                    ));
                    break;
                }
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// The same bodies mirrored (names kept): the joints named left now stand
/// on the right and map to the right canonical joints, from geometry.
#[test]
fn more_suites_mirrored_map_left_and_right_from_geometry() {
    let mut fails = Vec::new();
    for s in SUITES {
        let k = parse_skel(s.skel);
        let m = via_text(&k, &mirror(&k.clip()), s.name);
        let d = match detect_clip(&m) {
            Ok(d) => d,
            Err(e) => {
                fails.push(format!("{} mirrored: {e}", s.name));
                continue;
            }
        };
        let want: Vec<(Canonical, Vec<String>)> = expected(s)
            .into_iter()
            .map(|(k, v)| (swap_side(k), v))
            .collect();
        for e in map_errors(&d, &want) {
            fails.push(format!("{} mirrored: {e}", s.name));
        }
        // Names that state sides are reported as mirrored (a rig of bone
        // numbers has none to contradict).
        let sided = m.point_names().iter().any(|n| {
            use surfmotion::rig::names::{side, tokens};
            side(&tokens(n)).is_some()
        });
        if sided && !d.sides.contains("mirrored") {
            fails.push(format!("{} mirrored: sides {}", s.name, d.sides));
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// Non-humanoids are refused with "not a humanoid: …".
#[test]
fn more_non_humanoids_are_refused() {
    let mut fails = Vec::new();
    for (name, skel) in NOT_HUMANOIDS {
        let k = parse_skel(skel);
        let c = via_text(&k, &k.clip(), name);
        match detect_clip(&c) {
            Err(RigError::NotHumanoid { .. }) => {}
            Ok(d) => fails.push(format!(
                "{name} mapped as {}: {:?}",
                d.map.convention, d.map.joints
            )),
            Err(e) => fails.push(format!("{name}: {e}")),
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// `mocap rigmap` and `inspect --json` on every family written as a file
/// (its line ends and indentation): exit 0, the convention, the unit and
/// the up axis of the file; non-humanoids exit 1 with "not a humanoid".
#[test]
fn cli_reads_every_suite_in_its_unit_and_up_axis() {
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for s in SUITES {
        let k = parse_skel(s.skel);
        let p = dir.path().join(format!("{}.bvh", s.name));
        std::fs::write(&p, k.text(&k.clip())).unwrap();
        let o = std::process::Command::new(common::bin())
            .args(["mocap", "rigmap"])
            .arg(&p)
            .output()
            .unwrap();
        let out = String::from_utf8_lossy(&o.stdout);
        let line = out.lines().next().unwrap_or("");
        if !convention_ok(s.convention, line.trim_start_matches("convention: ")) {
            fails.push(format!(
                "{} rigmap: {}",
                s.name,
                out.lines().next().unwrap_or("")
            ));
        }
        let o = common::run_ok(
            std::process::Command::new(common::bin())
                .args(["inspect", "--json"])
                .arg(&p),
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        if !convention_ok(s.convention, v["convention"].as_str().unwrap_or("")) {
            fails.push(format!(
                "{} inspect: convention {}",
                s.name, v["convention"]
            ));
        }
        let up = if k.z_up() { "Z" } else { "Y" };
        if v["up"].as_str() != Some(up) {
            fails.push(format!(
                "{} inspect: up {} ({})",
                s.name, v["up"], v["up_reason"]
            ));
        }
        let m = v["units"]["metres_per_unit"].as_f64().unwrap_or(0.0);
        if (m / k.metres_per_unit() - 1.0).abs() > 1e-6 {
            fails.push(format!("{} inspect: units {}", s.name, v["units"]));
        }
    }
    for (name, skel) in NOT_HUMANOIDS {
        let k = parse_skel(skel);
        let p = dir.path().join(format!("{name}.bvh"));
        std::fs::write(&p, k.text(&k.clip())).unwrap();
        let o = std::process::Command::new(common::bin())
            .args(["mocap", "rigmap"])
            .arg(&p)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        if o.status.code() != Some(1) || !e.contains("not a humanoid: ") {
            fails.push(format!("{name}: exit {:?}: {e}", o.status.code()));
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// A non-humanoid's up axis comes from its feet on the ground, not from
/// head − pelvis (the Y-up T-rex, whose head is ahead of its pelvis, was
/// reported Z-up): each one written Y-up and Z-up is reported in its own
/// axis, or as unknown; the T-rex, the legs-only rig, the crab, the table
/// and the griffin, which stand on two or more feet, never as unknown. A
/// winged humanoid's `mocap rigmap` and `inspect` name the chains ignored.
#[test]
fn non_humanoids_report_their_up_axis_from_the_ground() {
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for (name, skel) in NOT_HUMANOIDS {
        for axes in ["y", "y-z", "zup-y", "zup+y"] {
            let mut k = parse_skel(skel);
            k.axes = axes.into();
            let p = dir.path().join(format!("{name}_{axes}.bvh"));
            std::fs::write(&p, k.text(&k.clip())).unwrap();
            let o = common::run_ok(
                std::process::Command::new(common::bin())
                    .args(["inspect", "--json"])
                    .arg(&p),
            );
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            let why = v["up_reason"].as_str().unwrap_or("");
            let want = if k.z_up() { "Z" } else { "Y" };
            let stands = [
                "trex_humanik_names",
                "legs_only",
                "crab",
                "table",
                "winged_quadruped",
            ]
            .contains(name);
            let unknown = why.starts_with("unknown");
            if (v["up"].as_str() != Some(want) && !unknown) || (stands && unknown) {
                fails.push(format!("{name} {axes}: up {} ({why})", v["up"]));
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
    let s = SUITES.iter().find(|s| s.name == "winged_unnamed").unwrap();
    let k = parse_skel(s.skel);
    let p = dir.path().join("winged.bvh");
    std::fs::write(&p, k.text(&k.clip())).unwrap();
    for verb in [&["mocap", "rigmap"][..], &["inspect"][..]] {
        let o = common::run_ok(std::process::Command::new(common::bin()).args(verb).arg(&p));
        let out = String::from_utf8_lossy(&o.stdout);
        let line = out
            .lines()
            .find(|l| l.contains("are neither arms nor the neck and are ignored: "))
            .unwrap_or("");
        assert!(
            ["LeftPinion1", "RightPinion1", "Drape1", "Dangle1"]
                .iter()
                .all(|c| line.contains(c)),
            "{verb:?}: {out}"
        );
    }
}

// ------------------------------------------------------------------ units

/// An MMD figure (Japanese and English bone names, both as given and
/// mirrored, and with a namespace) written in m, cm, mm, inches, feet and
/// MMD's own 8 cm unit reads to the same stature in every one (within 3%;
/// MMD units were read as decimetres, a 1.64 m figure as 2.05 m), and
/// `inspect` says which unit it assumed and why.
#[test]
fn an_mmd_figure_reads_to_one_stature_in_every_unit() {
    use surfmotion::rig::load::stature;
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for name in ["mmd_japanese", "mmd_english"] {
        let s = SUITES.iter().find(|s| s.name == name).unwrap();
        let k = parse_skel(s.skel);
        let c = k.clip();
        let map = detect_clip(&c).unwrap().map;
        let truth = stature(&c, &map).unwrap().0 * k.metres_per_unit();
        assert!((1.5..1.8).contains(&truth), "{name}: {truth} m");
        let spaced = c
            .clone()
            .edited(|p| {
                for j in &mut p.joints {
                    j.name = format!("Model|{}", j.name);
                }
            })
            .unwrap();
        for (variant, v) in [
            ("", c.clone()),
            (" mirrored", mirror(&c)),
            (" namespaced", spaced),
        ] {
            for (unit, m) in [
                ("m", 1.0),
                ("cm", 0.01),
                ("mm", 0.001),
                ("inch", 0.0254),
                ("ft", 0.3048),
                ("mmd", 0.08),
            ] {
                let w = common::skel::scaled(&v, k.metres_per_unit() / m);
                let p = dir.path().join(format!("{name}_{unit}.bvh"));
                std::fs::write(&p, format_bvh(&w)).unwrap();
                let got = load_clip(&p, &Default::default()).unwrap();
                let map = detect_clip(&got).unwrap().map;
                let h = stature(&got, &map).unwrap().0 * got.units().metres_per_unit;
                if (h / truth - 1.0).abs() > 0.03 {
                    fails.push(format!(
                        "{name}{variant} in {unit}: {h:.3} m, not {truth:.3} ({})",
                        got.units().reason
                    ));
                }
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
    // `inspect` names the unit, the stature and why.
    let p = dir.path().join("mmd_english_mmd.bvh");
    let o = common::run_ok(
        std::process::Command::new(common::bin())
            .args(["inspect", "--json"])
            .arg(&p),
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let why = v["units"]["reason"].as_str().unwrap_or("");
    assert_eq!(v["units"]["metres_per_unit"], 0.08, "{v}");
    assert!(
        why.contains("MMD bone names") && why.contains("human stature"),
        "{why}"
    );
}

// ------------------------------------------------- the walk on each skeleton

/// The canonical joint whose bone direction turns joint `c`'s rest into
/// the walk's rest (the limb bones: a T- or A-pose arm comes down; thighs
/// and shins of a skeleton whose legs splay a little come straight).
fn bone_child(c: Canonical) -> Option<Canonical> {
    use Canonical as C;
    Some(match c {
        C::LHip => C::LKnee,
        C::LKnee => C::LAnkle,
        C::RHip => C::RKnee,
        C::RKnee => C::RAnkle,
        C::LShoulder => C::LElbow,
        C::LElbow => C::LWrist,
        C::RShoulder => C::RElbow,
        C::RElbow => C::RWrist,
        _ => return None,
    })
}

/// The procedural walk written onto the skeleton `rest` (a clip of
/// `k`'s file, in its frame and unit) through its mapped joints `want`:
/// each mapped joint turns in the world as the walk's joint does from its
/// rest, after the swing taking this skeleton's rest limb bone onto the
/// walk's (T- and A-pose arms come down); joints between mapped ones
/// follow their nearest mapped ancestor, joints above the pelvis stay at
/// rest; the pelvis travels as the walk's, scaled by the legs' heights.
fn walk_onto(k: &Skel, rest: &Clip, want: &[(Canonical, Vec<String>)], walk: &Clip) -> Clip {
    let wmap = detect_clip(walk).unwrap().map;
    let (wposes, wrots) = wmap.poses_and_rotations(walk).unwrap();
    let wrest = wmap.rest_pose(walk).unwrap();
    let a = k.axes();
    let ai = a.inverse();
    let (trest, _) = rest.rest_positions();
    let joint_of = |c: Canonical| -> Option<usize> {
        want.iter()
            .find(|(k, _)| *k == c)
            .and_then(|(_, v)| v.first())
            .and_then(|n| rest.joint(n))
            .map(|j| j.idx())
    };
    let n = rest.joint_count();
    let mut owner: Vec<Option<Canonical>> = vec![None; n];
    for c in Canonical::ALL {
        if let Some(j) = joint_of(c) {
            owner[j] = Some(c);
        }
    }
    for j in 0..n {
        if owner[j].is_none()
            && let Some(p) = rest.joints()[j].parent
        {
            owner[j] = owner[p.idx()];
        }
    }
    // Swing of each canonical joint (walk frame).
    let mut swing = [DQuat::IDENTITY; Canonical::COUNT];
    for c in Canonical::ALL {
        if let (Some(ch), Some(j)) = (bone_child(c), joint_of(c))
            && let Some(cj) = joint_of(ch)
        {
            let dt = (ai * (trest[cj] - trest[j])).normalize();
            let dw = (wrest[ch.index()] - wrest[c.index()]).normalize();
            swing[c.index()] = DQuat::from_rotation_arc(dt, dw);
        }
    }
    use Canonical as C;
    for (w, e) in [(C::LWrist, C::LElbow), (C::RWrist, C::RElbow)] {
        swing[w.index()] = swing[e.index()];
    }
    let pj = joint_of(C::Pelvis).unwrap();
    let legs = |p: &[DVec3], pel: DVec3| pel.y - p.iter().map(|q| q.y).fold(f64::MAX, f64::min);
    let tall: Vec<DVec3> = trest.iter().map(|&p| ai * p).collect();
    let scale = legs(&tall, tall[pj]) / legs(&wrest, wrest[C::Pelvis.index()]);
    // The pelvis's own position channels carry the travel when it has
    // them (a ClipNeutral node above it stays put), else the root's do.
    let pelvis_moves = rest.joints()[pj].has_position_channels();
    let frames = walk.frame_count();
    let mut rot = Vec::with_capacity(frames * n);
    let mut tr = Vec::with_capacity(frames * n);
    for f in 0..frames {
        let world: Vec<DQuat> = (0..n)
            .map(|j| match owner[j] {
                Some(c) => {
                    let g = wrots[f][c.index()].unwrap_or(DQuat::IDENTITY);
                    a * (g * swing[c.index()]) * ai
                }
                None => DQuat::IDENTITY,
            })
            .collect();
        let travel = wposes[f][C::Pelvis.index()] - wrest[C::Pelvis.index()];
        let pelvis_at = trest[pj] + a * (travel * scale);
        for (j, joint) in rest.joints().iter().enumerate() {
            let pw = joint.parent.map_or(DQuat::IDENTITY, |p| world[p.idx()]);
            rot.push(pw.inverse() * world[j]);
            let above = joint.parent.map_or(DVec3::ZERO, |p| trest[p.idx()]);
            let t = if j == pj && pelvis_moves {
                pelvis_at - above
            } else if joint.parent.is_none() && !pelvis_moves {
                joint.offset + (pelvis_at - trest[pj])
            } else {
                joint.offset
            };
            tr.push(t);
        }
    }
    Clip::new(
        rest.joints().to_vec(),
        walk.frame_time(),
        rot,
        tr,
        rest.units().clone(),
        rest.up(),
        PointConvention::JointOrigins,
    )
    .unwrap()
}

/// A retargeted sequence seen from its own travel: positions relative to
/// the first frame's pelvis, turned about +Y so the travel is along +Z.
fn from_travel(poses: &[Pose]) -> Vec<Pose> {
    let p0 = poses[0][Canonical::Pelvis.index()];
    let d = poses.last().unwrap()[Canonical::Pelvis.index()] - p0;
    let yaw = d.x.atan2(d.z);
    let q = DQuat::from_rotation_y(-yaw);
    poses.iter().map(|p| p.map(|x| q * (x - p0))).collect()
}

/// The procedural walk written onto every family's skeleton (in its file's
/// frame, unit, channel layout, line ends) and retargeted onto the
/// procedural character as `retarget` reads a clip (`load_clip`: unit and
/// up axis guessed; detected map; reference pose; rotation transfer) gives
/// the character the walk the procedural skeleton itself gives it: every
/// joint within 6% of the character's height of it in every frame, seen
/// from the travel direction (a mirrored map swaps the legs by ~40%, a
/// wrong up axis or a backward walk moves everything), and the same
/// travel distance within 15%.
#[test]
fn the_walk_on_every_suite_skeleton_retargets_like_the_walk() {
    use surfmotion::embed::Embedding;
    use surfmotion::pose::retarget::{clip_poses, retarget};
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks, humanoid_mesh};
    let mesh = humanoid_mesh(DEMO_GRID);
    let rig = Embedding::new(&mesh, &humanoid_landmarks(&mesh), None).unwrap();
    let character: Pose = rig.joints().map(DVec3::from_array);
    let dir = tempfile::tempdir().unwrap();
    let walk = gait_clip(Gait::Walk, 2.0, 30.0);
    let drive = |path: &std::path::Path| -> Result<Vec<Pose>, String> {
        let mut c = load_clip(path, &Default::default()).map_err(|e| e.to_string())?;
        c.to_metres_y_up();
        let d = detect_clip(&c).map_err(|e| e.to_string())?;
        let cp = clip_poses(&c, &d.map).map_err(|e| e.to_string())?;
        Ok(retarget(&character, &cp.reference, &cp.poses)
            .into_iter()
            .map(|(p, _)| p)
            .collect())
    };
    let wpath = dir.path().join("walk.bvh");
    std::fs::write(&wpath, format_bvh(&walk)).unwrap();
    let base = from_travel(&drive(&wpath).unwrap());
    let h = rig.height();
    let mut fails = Vec::new();
    // This file's families with their expected maps; the fixtures'
    // families with their detected maps (checked against their expected
    // maps in tests/rig_mapping.rs).
    let mut cases: Vec<(String, Skel, Want)> = SUITES
        .iter()
        .map(|s| (s.name.to_string(), parse_skel(s.skel), expected(s)))
        .collect();
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/suites");
    let mut files: Vec<_> = std::fs::read_dir(&fixtures)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    for f in files {
        let name = f.file_stem().unwrap().to_string_lossy().to_string();
        let Some(k) = fixture_skel(&std::fs::read_to_string(&f).unwrap()) else {
            continue;
        };
        let Ok(d) = detect_clip(&via_text(&k, &k.clip(), &name)) else {
            continue; // the animals
        };
        let want = Canonical::ALL
            .iter()
            .map(|c| (*c, d.map.joints.get(c).into_iter().cloned().collect()))
            .collect();
        cases.push((format!("fixture {name}"), k, want));
    }
    for (name, k, want) in &cases {
        let rest = via_text(k, &k.clip(), name);
        let moved = walk_onto(k, &rest, want, &walk);
        let path = dir.path().join(format!("{}.bvh", name.replace(' ', "_")));
        std::fs::write(&path, k.text(&moved)).unwrap();
        let got = match drive(&path) {
            Ok(p) => from_travel(&p),
            Err(e) => {
                fails.push(format!("{name}: {e}"));
                continue;
            }
        };
        let (mut worst, mut at) = (0.0f64, String::new());
        for (f, (g, b)) in got.iter().zip(&base).enumerate() {
            let (pg, pb) = (g[0], b[0]);
            for c in Canonical::ALL {
                let e = ((g[c.index()] - pg) - (b[c.index()] - pb)).length() / h;
                if e > worst {
                    worst = e;
                    at = format!("{} frame {f}", c.name());
                }
            }
        }
        let dist = |p: &[Pose]| p.last().unwrap()[0].length();
        let ratio = dist(&got) / dist(&base);
        eprintln!("{name}: worst {worst:.3} H at {at}; travel ratio {ratio:.3}");
        if worst > 0.06 || !(0.85..=1.15).contains(&ratio) {
            fails.push(format!(
                "{name}: worst {worst:.3} H at {at}; travel ratio {ratio:.3}"
            ));
        }
        // Mirrored (x negated in the file, names kept): the character walks
        // the mirror image, its left leg doing what the right one did.
        let mpath = dir
            .path()
            .join(format!("{}_mirrored.bvh", name.replace(' ', "_")));
        std::fs::write(&mpath, k.text(&mirror(&moved))).unwrap();
        let got = match drive(&mpath) {
            Ok(p) => from_travel(&p),
            Err(e) => {
                fails.push(format!("{name} mirrored: {e}"));
                continue;
            }
        };
        let flip = |v: DVec3| DVec3::new(-v.x, v.y, v.z);
        let mut worst = 0.0f64;
        for (g, b) in got.iter().zip(&base) {
            for c in Canonical::ALL {
                let want = flip(b[swap_side(c).index()] - b[0]);
                worst = worst.max(((g[c.index()] - g[0]) - want).length() / h);
            }
        }
        eprintln!("{name} mirrored: worst {worst:.3} H");
        if worst > 0.06 {
            fails.push(format!("{name} mirrored: worst {worst:.3} H"));
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}
