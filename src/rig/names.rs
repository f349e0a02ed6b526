//! Joint-name normalisation and token matching: a joint name becomes
//! lower-case tokens, a side (left/right) and a body-part [`Role`].
//!
//! Names are only hints: [`super::structure`] decides which chain a joint
//! belongs to and which side it is on from the skeleton's geometry; the
//! role picks a joint inside a chain when the geometry leaves a choice
//! (spine vs. waist, collar vs. upper arm, wrist vs. hand).
//!
//! Families handled (examples): namespaces (`mixamorig7:Hips`,
//! `Armature|Hips`), common prefixes (`Character1_`, `Bip01 `, `CC_Base_`),
//! ASF bones (`lfemur`, `lhumerus`), Daz/Poser (`lShldr`, `lThigh`), SMPL
//! (`L_Hip`, `left_hip`), Kinect (`HipLeft`), Xsens (`RightUpperLeg`, `T8`),
//! Unity (`LeftUpperArm`), 3ds Max Biped (`Bip01 L Calf`), OptiTrack Motive
//! (`LUArm`, `LFArm`, `Ab`), VRoid (`J_Bip_C_Hips`), the Biovision sample
//! (`LeftLowArm`, `LeftLowLeg`).

/// Which side of the body a name says a joint is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

/// The body part a name denotes (side apart).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// `Hips`, `Pelvis`, `root`, `SpineBase`, unsided `hip`.
    Pelvis,
    /// A lower/mid spine joint, with a preference score (3 best):
    /// `Spine`/`abdomen`/`L3` 3, `Spine1`/`Spine01`/`abdomen2`/`abdomenUpper` 2,
    /// `Waist`/`L5`/`LowerBack` 1.
    Spine(u8),
    /// `Chest`, `Spine2`, `T8`, `UpperChest`, `thorax`.
    Chest,
    /// `Neck`, `lowerneck`.
    Neck,
    /// `Head`.
    Head,
    /// `Collar`, `Clavicle`.
    Collar,
    /// `Shoulder`: the upper arm when a collar exists beside it, else the collar.
    ShoulderWord,
    /// `UpperArm`, `Arm`, `Shldr`, `humerus`.
    UpperArm,
    /// `ForeArm`, `LowerArm`, `Elbow`, `radius`.
    Elbow,
    /// `Wrist`.
    Wrist,
    /// `Hand`.
    Hand,
    /// `Thigh`, `UpLeg`, `UpperLeg`, `femur`, sided `Hip`.
    Thigh,
    /// `Calf`, `Shin`, `Leg`, `LowerLeg`, `Knee`, `tibia`.
    Knee,
    /// `Ankle`.
    Ankle,
    /// `Foot`.
    Foot,
    /// `Toe`, `ToeBase`, `Toes`, `Ball`.
    Toe,
}

/// Tokens that mark a helper bone, never a canonical joint.
const HELPER: &[&str] = &[
    "twist",
    "roll",
    "share",
    "sharebone",
    "rigmesh",
    "mesh",
    "end",
    "nub",
    "dummy",
    "ik",
    "pole",
    "finger",
    "fingers",
    "thumb",
    "index",
    "middle",
    "ring",
    "pinky",
    "pinkie",
    "little",
    "eye",
    "eyes",
    "jaw",
    "tongue",
    "teeth",
    "facial",
    "face",
    "big",
    "nail",
    "hair",
    "ponytail",
    "breast",
    "weapon",
    "prop",
    "ctrl",
    "control",
    "target",
    "tip",
    "site",
    "helper",
    "bone_root",
    "ref",
    "reference",
    "tail",
    // Cloth and accessory chains (game and VRoid rigs hang them off the
    // hips and the chest beside the limbs). Not wings: a bird's or a
    // dragon's are its forelimbs, and the structure must see them.
    "cape",
    "cloak",
    "skirt",
    "coat",
    "cloth",
    "ribbon",
    "scarf",
    "carpal",
    "metacarpal",
    "lid",
    "brow",
    "lip",
    "cheek",
];

/// Leading tokens of rig prefixes (`Bip01 `, `CC_Base_`, `mixamorig`, `DEF-`,
/// VRoid's `J_Bip_`).
const RIG_PREFIX: &[&str] = &[
    "j",
    "bip",
    "cc",
    "base",
    "mixamorig",
    "character",
    "armature",
    "def",
    "rig",
    "sk",
    "skel",
];

/// Body words that may be fused to an ASF/Poser side letter (`lfemur`).
const FUSED: &[&str] = &[
    "femur", "tibia", "humerus", "radius", "wrist", "hand", "foot", "toes", "toe", "clavicle",
    "collar", "thigh", "shin", "shldr", "hipjoint", "fingers", "thumb", "forearm", "upperarm",
    "ankle", "knee", "elbow", "shoulder", "hip", "leg", "arm", "ulna", "calf",
];

/// Limb abbreviations that follow a capital side letter in one capital run
/// (OptiTrack Motive's `LUArm`, `LFArm`: left upper arm, left forearm),
/// which camelCase splitting leaves as `lu arm`.
const SIDE_ABBREV: &[(&str, &str)] = &[("u", "arm"), ("f", "arm")];

/// Strips a `namespace:` or `path|` prefix (the part after the last `:` or `|`).
pub fn strip_namespace(s: &str) -> &str {
    s.rsplit([':', '|']).next().unwrap_or(s).trim()
}

/// The longest prefix ending in a separator (`_`, ` `, `.`, `-`) shared by at
/// least 80% of the (namespace-stripped) names, if any; e.g. `Bip01 `,
/// `Character1_`, `CC_Base_`. O(n·len).
pub(crate) fn common_prefix(names: &[&str]) -> Option<String> {
    if names.len() < 2 {
        return None;
    }
    let mut counts: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for n in names {
        for (i, ch) in n.char_indices() {
            if matches!(ch, '_' | ' ' | '.' | '-') && i + 1 < n.len() {
                *counts.entry(&n[..=i]).or_default() += 1;
            }
        }
    }
    let need = (names.len() * 4).div_ceil(5).max(2);
    counts
        .into_iter()
        .filter(|(p, c)| *c >= need && p.len() >= 2)
        .max_by_key(|(p, c)| (p.len(), *c))
        .map(|(p, _)| p.to_string())
}

/// MikuMikuDance's standard bone words (Japanese), as the English words
/// the tokens know, longest first (`足首` before `足`, `手首` before `首`):
/// sides `左`/`右`, limb joints, twist (`捩`) and finger bones as helpers.
/// `足` (leg) is the thigh joint, `腕` (arm) the upper arm, `肩`
/// (shoulder) the clavicle. From public VMD/PMX standard-bone tables.
const MMD_WORDS: &[(&str, &str)] = &[
    ("つま先", "toe"),
    ("足首", "ankle"),
    ("手首", "wrist"),
    ("ひざ", "knee"),
    ("ひじ", "elbow"),
    ("親指", "thumb"),
    ("人指", "index"),
    ("中指", "middle"),
    ("薬指", "ring"),
    ("小指", "pinky"),
    ("上半身", "upper body"),
    ("下半身", "lower body"),
    ("左", "left"),
    ("右", "right"),
    ("足", "thigh"),
    ("腕", "upper arm"),
    ("肩", "clavicle"),
    ("首", "neck"),
    ("頭", "head"),
    ("目", "eye"),
    ("捩", "twist"),
];

/// A name with full-width letters and digits made ASCII (`ＩＫ` → `IK`)
/// and MMD's Japanese bone words replaced by English ones, each between
/// spaces (`左足首` → ` left  ankle `). ASCII names are returned as given.
fn ascii_words(name: &str) -> std::borrow::Cow<'_, str> {
    if name.is_ascii() {
        return std::borrow::Cow::Borrowed(name);
    }
    let mut s: String = name
        .chars()
        .map(|c| match c {
            '\u{ff01}'..='\u{ff5e}' => char::from_u32(c as u32 - 0xfee0).unwrap_or(c),
            c => c,
        })
        .collect();
    for (jp, en) in MMD_WORDS {
        if s.contains(jp) {
            s = s.replace(jp, &format!(" {en} "));
        }
    }
    std::borrow::Cow::Owned(s)
}

/// MikuMikuDance's standard trunk bones, as the tokens of their English
/// names and their Japanese names: all parents (全ての親), centre
/// (センター), groove (グルーブ), upper body (上半身), lower body (下半身).
const MMD_TRUNK: &[(&str, &str)] = &[
    ("all parents", "全ての親"),
    ("center", "センター"),
    ("groove", "グルーブ"),
    ("upper body", "上半身"),
    ("lower body", "下半身"),
];

/// True when at least two of MikuMikuDance's standard trunk bones
/// ([`MMD_TRUNK`]) name joints of the rig (namespaces stripped), in
/// Japanese or in English: a clip exported from MMD, whose length unit is
/// 8 cm ([`crate::mocap::units::MMD_UNIT_M`]).
pub(crate) fn mmd_rig(names: &[String]) -> bool {
    MMD_TRUNK
        .iter()
        .filter(|(en, jp)| {
            names.iter().any(|n| {
                let n = strip_namespace(n);
                n == *jp || tokens(n).join(" ") == *en
            })
        })
        .count()
        >= 2
}

/// Splits a name into lower-case tokens at separators, camelCase humps and
/// letter/digit boundaries (`LeftUpLeg` → `left up leg`, `Spine01` →
/// `spine 01`, `LThumb` → `l thumb`, `lfemur` → `l femur`; MMD's Japanese
/// `左足首` → `left ankle`, see [`MMD_WORDS`]).
pub fn tokens(name: &str) -> Vec<String> {
    let name = ascii_words(name);
    let chars: Vec<char> = name.chars().collect();
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    let push = |cur: &mut String, out: &mut Vec<String>| {
        if !cur.is_empty() {
            out.push(std::mem::take(cur).to_ascii_lowercase());
        }
    };
    for (i, &c) in chars.iter().enumerate() {
        if !c.is_ascii_alphanumeric() {
            push(&mut cur, &mut out);
            continue;
        }
        if let Some(&p) = i.checked_sub(1).and_then(|k| chars.get(k)) {
            let next_lower = chars.get(i + 1).is_some_and(|n| n.is_ascii_lowercase());
            let boundary = (p.is_ascii_lowercase() && c.is_ascii_uppercase())
                || (p.is_ascii_uppercase() && c.is_ascii_uppercase() && next_lower)
                || (p.is_ascii_digit() != c.is_ascii_digit() && p.is_ascii_alphanumeric());
            if boundary {
                push(&mut cur, &mut out);
            }
        }
        cur.push(c);
    }
    push(&mut cur, &mut out);
    // Fused side letters: `lfemur`, `rhand`, `lhipjoint`.
    let mut split = Vec::with_capacity(out.len());
    let mut out = out.into_iter().peekable();
    while let Some(t) = out.next() {
        // `LUArm` → `lu arm` → `l uarm`.
        let abbrev = t.len() == 2
            && (t.starts_with('l') || t.starts_with('r'))
            && out
                .peek()
                .is_some_and(|n| SIDE_ABBREV.contains(&(&t[1..], n.as_str())));
        if abbrev {
            let next = out.next().unwrap_or_default();
            split.push(t[..1].to_string());
            split.push(format!("{}{next}", &t[1..]));
            continue;
        }
        let fused = (t.starts_with('l') || t.starts_with('r'))
            && t.len() > 2
            && FUSED.contains(&&t[1..])
            && !FUSED.contains(&t.as_str());
        if fused {
            split.push(t[..1].to_string());
            split.push(t[1..].to_string());
        } else {
            split.push(t);
        }
    }
    split
}

/// A vertebra label (`L5`, `L3`, `T12`, `T8`, `C7`; H-Anim's `vl5`, `vt10`,
/// `vc7`): its letter and number.
fn vertebra(tokens: &[String]) -> Option<(char, u32)> {
    match tokens {
        [a, n] if matches!(a.as_str(), "l" | "t" | "c" | "vl" | "vt" | "vc") => {
            Some((a.chars().last()?, n.parse().ok()?))
        }
        _ => None,
    }
}

/// The side a name's tokens state, if exactly one.
pub fn side(tokens: &[String]) -> Option<Side> {
    if vertebra(tokens).is_some() {
        return None;
    }
    let l = tokens.iter().any(|t| t == "l" || t == "left" || t == "lft");
    let r = tokens.iter().any(|t| t == "r" || t == "right" || t == "rt");
    match (l, r) {
        (true, false) => Some(Side::Left),
        (false, true) => Some(Side::Right),
        _ => None,
    }
}

/// True for helper bones (twist, roll, share, mesh attachments, end/nub
/// markers, IK targets, fingers, face): never a canonical joint.
pub fn is_helper(tokens: &[String]) -> bool {
    tokens.iter().any(|t| HELPER.contains(&t.as_str()))
        || tokens.windows(2).any(|w| w[0] == "hand" && w[1] == "tip")
}

/// The body part the tokens name, if any (helpers have none).
pub(crate) fn role(tokens: &[String]) -> Option<Role> {
    if is_helper(tokens) {
        return None;
    }
    if let Some((c, n)) = vertebra(tokens) {
        return match (c, n) {
            ('l', 3) => Some(Role::Spine(3)),
            ('l', _) => Some(Role::Spine(1)),
            ('t', 8) | ('t', 7) | ('t', 6) => Some(Role::Chest),
            ('t', _) => Some(Role::Spine(1)),
            _ => Some(Role::Neck),
        };
    }
    let has = |w: &str| tokens.iter().any(|t| t == w);
    let sided = side(tokens).is_some();
    let num: Option<u32> = tokens.iter().find_map(|t| t.parse().ok());
    let mut words: Vec<&str> = tokens
        .iter()
        .map(String::as_str)
        .filter(|t| !matches!(*t, "l" | "r" | "left" | "right" | "lft" | "rt"))
        .filter(|t| t.parse::<u32>().is_err())
        .collect();
    // VRoid's centre marker (`J_Bip_C_Hips`).
    if words.len() > 1 {
        words.retain(|t| *t != "c");
    }
    // Rig prefixes left over when not every joint carries them.
    while words.len() > 1 && RIG_PREFIX.contains(&words[0]) {
        words.remove(0);
    }
    let w = words.join("");
    Some(match w.as_str() {
        "hipjoint" => return None,
        "hips" | "pelvis" | "root" | "spinebase" | "sacroiliac" | "hip" if !sided => Role::Pelvis,
        "spine" | "abdomen" | "abdomenlower" | "spinelower" | "ab" => match num {
            None | Some(0) => Role::Spine(3),
            Some(1) if w == "abdomen" => Role::Spine(3),
            Some(2) if w == "abdomen" => Role::Spine(2),
            Some(1) => Role::Spine(2),
            _ => Role::Chest,
        },
        "spinemid" | "abdomenupper" => Role::Spine(2),
        "waist" | "lowerback" | "back" => Role::Spine(1),
        "chest" | "upperchest" | "thorax" | "spineshoulder" | "spineupper" | "upperback"
        | "chestupper" | "chestlower" => Role::Chest,
        "neck" | "lowerneck" | "neckbase" | "necklower" => Role::Neck,
        "head" => Role::Head,
        "collar" | "clavicle" | "shoulderblade" | "scapula" => Role::Collar,
        "shoulder" => Role::ShoulderWord,
        "upperarm" | "arm" | "shldr" | "humerus" | "uparm" | "shldrbend" | "uarm" => Role::UpperArm,
        "forearm" | "lowerarm" | "elbow" | "radius" | "ulna" | "forearmbend" | "lowarm"
        | "loarm" | "farm" => Role::Elbow,
        "wrist" => Role::Wrist,
        "hand" => Role::Hand,
        "thigh" | "upleg" | "upperleg" | "femur" | "hip" | "thighbend" => Role::Thigh,
        "calf" | "shin" | "leg" | "lowerleg" | "knee" | "tibia" | "loleg" | "lowleg" => Role::Knee,
        "ankle" => Role::Ankle,
        "foot" => Role::Foot,
        "toe" | "toebase" | "toes" | "ball" => Role::Toe,
        _ => {
            if has("toe") || has("toes") {
                Role::Toe
            } else {
                return None;
            }
        }
    })
}

/// Tokens of every name after stripping namespaces and a common prefix.
pub(crate) fn all_tokens(names: &[String]) -> Vec<Vec<String>> {
    let stripped: Vec<&str> = names.iter().map(|n| strip_namespace(n)).collect();
    let prefix = common_prefix(&stripped);
    stripped
        .iter()
        .map(|s| {
            let s = match &prefix {
                Some(p) if s.len() > p.len() => s.strip_prefix(p.as_str()).unwrap_or(s),
                _ => s,
            };
            tokens(s)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(s: &str) -> Vec<String> {
        tokens(s)
    }

    #[test]
    fn tokens_split_camel_digits_and_separators() {
        assert_eq!(t("LeftUpLeg"), ["left", "up", "leg"]);
        assert_eq!(t("CC_Base_L_Thigh"), ["cc", "base", "l", "thigh"]);
        assert_eq!(t("Spine01"), ["spine", "01"]);
        assert_eq!(t("LThumb"), ["l", "thumb"]);
        assert_eq!(t("lfemur"), ["l", "femur"]);
        assert_eq!(t("lShldr"), ["l", "shldr"]);
        assert_eq!(t("HipLeft"), ["hip", "left"]);
        assert_eq!(t("UpperLeg_L"), ["upper", "leg", "l"]);
        assert_eq!(t("hand.R"), ["hand", "r"]);
        assert_eq!(t("左足首"), ["left", "ankle"]);
        assert_eq!(t("右腕捩"), ["right", "upper", "arm", "twist"]);
        assert_eq!(t("左つま先ＩＫ"), ["left", "toe", "ik"]);
        assert_eq!(t("上半身2"), ["upper", "body", "2"]);
    }

    #[test]
    fn sides_and_roles_of_each_family() {
        let cases: &[(&str, Option<Side>, Option<Role>)] = &[
            ("LeftUpLeg", Some(Side::Left), Some(Role::Thigh)),
            ("RightLeg", Some(Side::Right), Some(Role::Knee)),
            ("lfemur", Some(Side::Left), Some(Role::Thigh)),
            ("rtibia", Some(Side::Right), Some(Role::Knee)),
            ("lShldr", Some(Side::Left), Some(Role::UpperArm)),
            ("L_Hip", Some(Side::Left), Some(Role::Thigh)),
            ("left_hip", Some(Side::Left), Some(Role::Thigh)),
            ("Pelvis", None, Some(Role::Pelvis)),
            ("hip", None, Some(Role::Pelvis)),
            ("HipLeft", Some(Side::Left), Some(Role::Thigh)),
            ("KneeLeft", Some(Side::Left), Some(Role::Knee)),
            ("FootLeft", Some(Side::Left), Some(Role::Foot)),
            ("RightUpperLeg", Some(Side::Right), Some(Role::Thigh)),
            ("T8", None, Some(Role::Chest)),
            ("L3", None, Some(Role::Spine(3))),
            ("LowerArm_L", Some(Side::Left), Some(Role::Elbow)),
            ("L Calf", Some(Side::Left), Some(Role::Knee)),
            ("LeftForeArmRoll", Some(Side::Left), None),
            ("CC_Base_L_UpperarmTwist01", Some(Side::Left), None),
            ("LeftHandIndex1", Some(Side::Left), None),
            ("lhipjoint", Some(Side::Left), None),
            ("SpineBase", None, Some(Role::Pelvis)),
            ("L5", None, Some(Role::Spine(1))),
            ("Bip01 L Thigh", Some(Side::Left), Some(Role::Thigh)),
            ("mixamorig:LeftToe_End", Some(Side::Left), None),
            // Daz Genesis 1-8.
            ("hip", None, Some(Role::Pelvis)),
            ("pelvis", None, Some(Role::Pelvis)),
            ("abdomen", None, Some(Role::Spine(3))),
            ("abdomen2", None, Some(Role::Spine(2))),
            ("abdomenLower", None, Some(Role::Spine(3))),
            ("abdomenUpper", None, Some(Role::Spine(2))),
            ("chestLower", None, Some(Role::Chest)),
            ("chestUpper", None, Some(Role::Chest)),
            ("neckLower", None, Some(Role::Neck)),
            ("lCollar", Some(Side::Left), Some(Role::Collar)),
            ("lShldrBend", Some(Side::Left), Some(Role::UpperArm)),
            ("lShldrTwist", Some(Side::Left), None),
            ("rForearmBend", Some(Side::Right), Some(Role::Elbow)),
            ("lForeArm", Some(Side::Left), Some(Role::Elbow)),
            ("lForearmTwist", Some(Side::Left), None),
            ("lThighBend", Some(Side::Left), Some(Role::Thigh)),
            ("rThighTwist", Some(Side::Right), None),
            ("lShin", Some(Side::Left), Some(Role::Knee)),
            ("lToe", Some(Side::Left), Some(Role::Toe)),
            ("lBigToe", Some(Side::Left), None),
            // Unreal: `_l` suffixes.
            ("thigh_l", Some(Side::Left), Some(Role::Thigh)),
            ("ball_r", Some(Side::Right), Some(Role::Toe)),
            ("upperarm_l", Some(Side::Left), Some(Role::UpperArm)),
            // OptiTrack Motive: a side letter fused to an abbreviation.
            ("LUArm", Some(Side::Left), Some(Role::UpperArm)),
            ("RFArm", Some(Side::Right), Some(Role::Elbow)),
            ("Ab", None, Some(Role::Spine(3))),
            ("LShin", Some(Side::Left), Some(Role::Knee)),
            // The Biovision sample.
            ("LeftLowArm", Some(Side::Left), Some(Role::Elbow)),
            ("RightLowLeg", Some(Side::Right), Some(Role::Knee)),
            ("LeftUpArm", Some(Side::Left), Some(Role::UpperArm)),
            // VRoid: `J_Bip_` prefix, `C` for the centre line.
            ("J_Bip_C_Hips", None, Some(Role::Pelvis)),
            ("J_Bip_C_UpperChest", None, Some(Role::Chest)),
            ("J_Bip_L_UpperLeg", Some(Side::Left), Some(Role::Thigh)),
            ("J_Bip_R_LowerArm", Some(Side::Right), Some(Role::Elbow)),
            ("C7", None, Some(Role::Neck)),
            // H-Anim.
            ("vl5", None, Some(Role::Spine(1))),
            ("vt6", None, Some(Role::Chest)),
            ("sacroiliac", None, Some(Role::Pelvis)),
            ("l_talocrural", Some(Side::Left), None),
            // Perception Neuron finger roots are helpers.
            ("RightInHandIndex", Some(Side::Right), None),
        ];
        for (n, s, r) in cases {
            let tk = t(n);
            assert_eq!(side(&tk), *s, "{n}: {tk:?}");
            assert_eq!(role(&tk), *r, "{n}: {tk:?}");
        }
    }

    #[test]
    fn common_prefixes_are_found_and_namespaces_stripped() {
        let n = [
            "Bip01",
            "Bip01 Pelvis",
            "Bip01 Spine",
            "Bip01 L Thigh",
            "Bip01 R Thigh",
        ];
        assert_eq!(common_prefix(&n).as_deref(), Some("Bip01 "));
        assert_eq!(strip_namespace("mixamorig7:Hips"), "Hips");
        assert_eq!(strip_namespace("Armature|Hips"), "Hips");
        assert_eq!(common_prefix(&["Hips", "Spine"]), None);
    }
}
