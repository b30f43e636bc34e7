//! Tethered climbing teams (Morad, Kalita, Thangavelautham, "Planning and Navigation of Climbing Robots in
//! Low-Gravity Environments", IEEE Aerospace 2018, sections III-VI).

pub mod dstar_lite;
