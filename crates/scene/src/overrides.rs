//! [`Overrides`]: the values given outside a scene file (on the command
//! line) that replace the file's, and, with the `clap` feature, their
//! command-line flags, shared by `prism render`, `prism view` and
//! `prism info`.

use prism_geometry::glam::Vec3;
use prism_shade::PixelFilter;

/// Values given outside the scene file (on the command line) that replace
/// the file's. The loader applies them once, to
/// [`crate::LoadedScene::settings`]; errors in them are reported as
/// [`crate::SceneError::Option`], naming the flag (`--width`,
/// `--camera-pos`, ...).
///
/// With the `clap` feature this is also the flags' definition
/// (`#[command(flatten)]`): `--width W`, `--height H`, `--spp N` (also `-s N`, `--samples N`),
/// `--max-depth N`, `--threads N`, `--fog` / `--no-fog`,
/// `--camera-pos X,Y,Z`, `--look-at X,Y,Z`, `--up X,Y,Z`, `--fov DEGREES`,
/// `--filter NAME`, `--adaptive THRESHOLD`, `--camera NAME`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Image width. If only one of width and height is given, the other
    /// follows the scene's aspect ratio.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Maximum recursion depth.
    pub max_depth: Option<u32>,
    /// Worker threads (`None`: every core).
    pub threads: Option<usize>,
    /// Fog on or off. On in a scene without `[fog]` adds a linear white
    /// fog reaching total at 1.5 times the distance to the farthest corner
    /// of the scene's bounds, or 3 times the distance to the camera's
    /// look-at point in a scene of planes alone (with a warning).
    pub fog: Option<bool>,
    /// Camera position (`--camera-pos`); must be finite.
    pub camera_pos: Option<Vec3>,
    /// The point the camera looks at, at the centre of the image
    /// (`--look-at`); must be finite and differ from the position.
    pub look_at: Option<Vec3>,
    /// The camera's up direction (`--up`); must be finite, non-zero and
    /// not parallel to the view direction.
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees (`--fov`), strictly between 0
    /// and 180.
    pub fov: Option<f32>,
    /// The pixel filter (`--filter box|gaussian|blackman-harris`).
    pub filter: Option<PixelFilter>,
    /// Adaptive supersampling threshold (`--adaptive THRESHOLD`), finite
    /// and at least 0.
    pub adaptive: Option<f32>,
    /// The scene camera to use (`--camera NAME`), by its `name`; the
    /// default is the file's first camera.
    pub camera: Option<CameraName>,
}

/// A camera's name as `--camera` gives it: up to [`CameraName::MAX_LEN`]
/// bytes of UTF-8, held inline so that [`Overrides`] stays `Copy`.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CameraName {
    len: u8,
    bytes: [u8; CameraName::MAX_LEN],
}

impl CameraName {
    /// The longest name, in bytes.
    pub const MAX_LEN: usize = 64;

    /// The name `s`.
    ///
    /// # Errors
    /// A message if `s` is empty or longer than [`CameraName::MAX_LEN`] bytes.
    pub fn new(s: &str) -> Result<Self, String> {
        let len = s.len();
        if len == 0 || len > Self::MAX_LEN {
            return Err(format!("a camera name has 1 to {} bytes, got {len}", Self::MAX_LEN));
        }
        let mut bytes = [0; Self::MAX_LEN];
        bytes[..len].copy_from_slice(s.as_bytes());
        Ok(Self { len: len as u8, bytes })
    }

    /// The name.
    #[must_use]
    pub fn as_str(&self) -> &str {
        self.bytes.get(..usize::from(self.len)).and_then(|b| std::str::from_utf8(b).ok()).unwrap_or("")
    }
}

impl std::fmt::Debug for CameraName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl std::fmt::Display for CameraName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `X,Y,Z`: three comma-separated numbers (checked to be finite by the
/// loader), the form of `--camera-pos`, `--look-at` and `--up`.
///
/// # Errors
/// A message naming what is wrong.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x, y, z] = parts.as_slice() else {
        return Err(format!("expected three comma-separated numbers X,Y,Z, got {} values", parts.len()));
    };
    let num = |t: &str| t.parse::<f32>().map_err(|_| format!("`{t}` is not a number (expected X,Y,Z)"));
    Ok(Vec3::new(num(x)?, num(y)?, num(z)?))
}

/// A command-line flag's whole number of at least `min`: a negative one is
/// refused as negative and a huge one as over `u64::MAX`, not as outside
/// `0..=4294967295`, which names no real limit. For `--max-pixels`; the
/// `u32` flags take [`whole_u32`].
///
/// # Errors
/// The words for clap's message: "cannot be negative", "is over N", "must
/// be at least N" or "expected a whole number".
pub fn whole_number(s: &str, min: u64) -> Result<u64, String> {
    let s = s.trim();
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    let v = match s.strip_prefix('-') {
        Some(t) if digits(t) => return Err("cannot be negative".into()),
        _ if digits(s) => s.parse::<u64>().map_err(|_| format!("is over {}", u64::MAX))?,
        _ => s.parse::<u64>().map_err(|_| "expected a whole number".to_string())?,
    };
    if v < min { Err(format!("must be at least {min}")) } else { Ok(v) }
}

/// [`whole_number`] for a `u32` flag (`--width`, `--spp`, `--max-spp`, …).
///
/// # Errors
/// As [`whole_number`], "is over 4294967295" past `u32::MAX`.
pub fn whole_u32(s: &str, min: u32) -> Result<u32, String> {
    let over = || format!("is over {}", u32::MAX);
    match whole_number(s, u64::from(min)) {
        Ok(v) => u32::try_from(v).map_err(|_| over()),
        Err(e) if e.starts_with("is over") => Err(over()),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
#[test]
fn whole_numbers_name_what_is_wrong() {
    assert_eq!(whole_u32("7", 1), Ok(7));
    assert_eq!(whole_u32("0", 1), Err("must be at least 1".into()));
    assert_eq!(whole_u32("-2", 1), Err("cannot be negative".into()));
    assert_eq!(whole_u32("4294967296", 1), Err("is over 4294967295".into()));
    assert_eq!(whole_number("4294967296", 1), Ok(4_294_967_296));
    assert_eq!(whole_number("99999999999999999999", 0), Err("is over 18446744073709551615".into()));
    assert_eq!(whole_u32("99999999999999999999", 0), Err("is over 4294967295".into()));
    assert_eq!(whole_u32("1e3", 0), Err("expected a whole number".into()));
}

#[cfg(feature = "clap")]
pub use cli::Named;

#[cfg(feature = "clap")]
mod cli {
    use super::{CameraName, Overrides, parse_vec3};
    use clap::builder::{PossibleValue, TypedValueParser};
    use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches, value_parser};

    /// A flag whose values are names (`--filter`, `--tonemap`): `parser`
    /// decides, with its own message, and `names` are the values shell
    /// completion offers and `--help` lists.
    #[derive(Clone)]
    pub struct Named<P> {
        /// The parser of a value.
        pub parser: P,
        /// The names it accepts.
        pub names: Vec<&'static str>,
    }

    impl<P: TypedValueParser> TypedValueParser for Named<P> {
        type Value = P::Value;

        fn parse_ref(
            &self,
            cmd: &Command,
            arg: Option<&Arg>,
            value: &std::ffi::OsStr,
        ) -> Result<Self::Value, clap::Error> {
            self.parser.parse_ref(cmd, arg, value)
        }

        fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
            Some(Box::new(self.names.iter().map(|n| PossibleValue::new(*n))))
        }
    }

    /// A flag's whole number (`--width`, `--spp`, …; [`super::whole_u32`]).
    fn whole_number(s: &str) -> Result<u32, String> {
        super::whole_u32(s, 0)
    }

    /// `--fog` and `--no-fog` are two flags of the one field
    /// [`Overrides::fog`], so the flags are declared here rather than derived.
    impl Args for Overrides {
        fn augment_args(cmd: Command) -> Command {
            let vec3 = |id: &'static str, help: &'static str| {
                Arg::new(id)
                    .long(id)
                    .value_name("X,Y,Z")
                    .value_parser(parse_vec3)
                    .allow_hyphen_values(true)
                    .help(help)
            };
            cmd.arg(
                Arg::new("width")
                    .long("width")
                    .value_name("W")
                    .value_parser(whole_number)
                    .help("Image width in pixels (alone: the height keeps the scene's aspect ratio)"),
            )
            .arg(
                Arg::new("height")
                    .long("height")
                    .value_name("H")
                    .value_parser(whole_number)
                    .help("Image height in pixels (alone: the width keeps the scene's aspect ratio)"),
            )
            .arg(
                Arg::new("spp")
                    .long("spp")
                    .short('s')
                    .visible_alias("samples")
                    .value_name("N")
                    .value_parser(whole_number)
                    .help("Samples per pixel"),
            )
            .arg(
                Arg::new("fog")
                    .long("fog")
                    .action(ArgAction::SetTrue)
                    .conflicts_with("no-fog")
                    .help("Turn fog on (adds a default linear fog if the scene has none)"),
            )
            .arg(
                Arg::new("no-fog").long("no-fog").action(ArgAction::SetTrue).help("Turn the scene's fog off"),
            )
            .arg(
                Arg::new("threads")
                    .long("threads")
                    .value_name("N")
                    .value_parser(value_parser!(u16).range(1..=4096))
                    .help("Worker threads [default: every core]"),
            )
            .arg(
                Arg::new("max-depth")
                    .long("max-depth")
                    .value_name("N")
                    .value_parser(whole_number)
                    .help("Maximum recursion depth of reflected, refracted and see-through rays"),
            )
            .arg(vec3("camera-pos", "Camera position, replacing the scene's"))
            .arg(vec3("look-at", "The point at the centre of the image, replacing the scene's"))
            .arg(vec3("up", "The camera's up direction, replacing the scene's"))
            .arg(
                Arg::new("fov")
                    .long("fov")
                    .value_name("DEGREES")
                    .value_parser(value_parser!(f32))
                    .allow_hyphen_values(true)
                    .help("Vertical field of view in degrees, strictly between 0 and 180"),
            )
            .arg(
                Arg::new("filter")
                    .long("filter")
                    .value_name("NAME")
                    .value_parser(Named {
                        parser: |s: &str| s.parse::<prism_shade::PixelFilter>().map_err(|e| e.to_string()),
                        names: prism_shade::PixelFilter::ALL.map(prism_shade::PixelFilter::name).to_vec(),
                    })
                    // Named in the help's own words; completion offers them.
                    .hide_possible_values(true)
                    .help("Pixel filter: box, gaussian or blackman-harris [default: the scene's, else box]"),
            )
            .arg(
                Arg::new("adaptive")
                    .long("adaptive")
                    .value_name("THRESHOLD")
                    .value_parser(value_parser!(f32))
                    .allow_hyphen_values(true)
                    .help("Adaptive supersampling: 4 samples per pixel, the rest of --spp only where two differ by more than THRESHOLD"),
            )
            .arg(
                Arg::new("camera")
                    .long("camera")
                    .value_name("NAME")
                    .value_parser(|s: &str| CameraName::new(s))
                    .help("The scene's camera of this name [default: its first camera]"),
            )
        }

        fn augment_args_for_update(cmd: Command) -> Command {
            Self::augment_args(cmd)
        }
    }

    impl FromArgMatches for Overrides {
        fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
            Ok(Self {
                width: m.get_one("width").copied(),
                height: m.get_one("height").copied(),
                spp: m.get_one("spp").copied(),
                max_depth: m.get_one("max-depth").copied(),
                threads: m.get_one::<u16>("threads").map(|&t| usize::from(t)),
                fog: match (m.get_flag("fog"), m.get_flag("no-fog")) {
                    (true, _) => Some(true),
                    (_, true) => Some(false),
                    _ => None,
                },
                camera_pos: m.get_one("camera-pos").copied(),
                look_at: m.get_one("look-at").copied(),
                up: m.get_one("up").copied(),
                fov: m.get_one("fov").copied(),
                filter: m.get_one("filter").copied(),
                adaptive: m.get_one("adaptive").copied(),
                camera: m.get_one("camera").copied(),
            })
        }

        fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
            *self = Self::from_arg_matches(m)?;
            Ok(())
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use prism_geometry::glam::Vec3;

        /// As prism's subcommands, which read `--spp -1` as a value.
        #[derive(clap::Parser)]
        #[command(allow_negative_numbers = true)]
        struct Cli {
            #[command(flatten)]
            overrides: Overrides,
        }

        fn parse(args: &[&str]) -> Result<Overrides, clap::Error> {
            use clap::Parser;
            Cli::try_parse_from(std::iter::once("prism").chain(args.iter().copied())).map(|c| c.overrides)
        }

        #[test]
        fn flags_fill_the_overrides() {
            assert_eq!(parse(&[]).unwrap(), Overrides::default());
            let o = parse(&[
                "--width",
                "40",
                "--spp",
                "3",
                "--no-fog",
                "--threads",
                "2",
                "--camera-pos",
                "-1,2.5,3",
                "--fov",
                "-5",
            ])
            .unwrap();
            assert_eq!(o.width, Some(40));
            assert_eq!(o.height, None);
            assert_eq!(o.spp, Some(3));
            assert_eq!(o.fog, Some(false));
            assert_eq!(o.threads, Some(2));
            assert_eq!(o.camera_pos, Some(Vec3::new(-1.0, 2.5, 3.0)));
            assert_eq!(o.fov, Some(-5.0), "range checks are the loader's, naming the flag");
            assert_eq!(parse(&["--fog"]).unwrap().fog, Some(true));
            assert_eq!(parse(&["--samples", "7"]).unwrap().spp, Some(7));
            assert_eq!(parse(&["-s", "9"]).unwrap().spp, Some(9));
            assert!(parse(&["--fog", "--no-fog"]).is_err());
            assert!(parse(&["--threads", "0"]).is_err());
            assert!(parse(&["--up", "1,2"]).is_err());
            for flag in ["--width", "--height", "--spp", "--max-depth"] {
                let e = parse(&[flag, "-3"]).unwrap_err().to_string();
                assert!(e.contains("cannot be negative") && !e.contains("4294967295"), "{flag}: {e}");
                assert!(parse(&[flag, "2.5"]).unwrap_err().to_string().contains("expected a whole number"));
                assert!(parse(&[flag, "4294967296"]).unwrap_err().to_string().contains("is over 4294967295"));
                let huge = "99999999999999999999999";
                assert!(parse(&[flag, huge]).unwrap_err().to_string().contains("is over 4294967295"));
                let e = parse(&[flag, &format!("-{huge}")]).unwrap_err().to_string();
                assert!(e.contains("cannot be negative"), "{flag}: {e}");
            }
            assert_eq!(
                parse(&["--camera", "top"]).unwrap().camera.map(|c| c.to_string()),
                Some("top".into())
            );
            assert!(parse(&["--camera", ""]).is_err());
            assert!(parse(&["--camera", &"x".repeat(65)]).is_err());
        }

        #[test]
        fn filter_and_adaptive_flags() {
            let o = parse(&["--filter", "gaussian", "--adaptive", "0.1"]).unwrap();
            assert_eq!(o.filter, Some(prism_shade::PixelFilter::Gaussian));
            assert_eq!(o.adaptive, Some(0.1));
            assert_eq!(
                parse(&["--filter", "blackman-harris"]).unwrap().filter,
                Some(prism_shade::PixelFilter::BlackmanHarris)
            );
            let err = parse(&["--filter", "sinc"]).unwrap_err().to_string();
            assert!(err.contains("unknown pixel filter `sinc`"), "{err}");
            assert_eq!(
                parse(&["--adaptive", "-1"]).unwrap().adaptive,
                Some(-1.0),
                "range checks are the loader's"
            );
        }
    }
}
