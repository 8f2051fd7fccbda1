/*
 * rp_render.hpp - rendering the paper's six-camera rig moving through a textured scene (host
 * only, C++ with OpenCV). Used by rigpose-render (writes a replay folder), rigpose-e2e (renders
 * in memory and runs the image pipeline) and their tests.
 *
 * Scene ("shell"): the paper's shell of points made a closed textured surface around the start,
 * at the same depths: in direction u (unit vector from the world origin) the surface lies at
 * radius r(u) = r_mid + r_amp s(u), s a smooth random function in [-1, 1], so the radii span
 * the simulation's shell 0.667..1 m (r_amp = 0: a sphere of radius r_mid). r and the surface's
 * grey level (albedo) are functions of u only, stored as cube maps (one square image per face,
 * bilinear lookups; the faces carry a border so that a lookup never crosses a face). The albedo
 * is 3-D gradient noise of the point r_mid u (metres): several octaves from 0.25 m down to 6 mm
 * plus soft-edged patches ("stains") at two scales; deterministic from the seed.
 *
 * Rendering is per-pixel ray casting, exact up to the cube maps' interpolation: each (sub)pixel's
 * ray comes from rp_cam_unproject (the rig's distortion model), goes through the rig pose into
 * the world, and is intersected with the surface by a secant iteration on |C + t d| = r(dir).
 * A pixel is the mean of ss x ss sub-pixel samples (box filter over the pixel's area).
 * Conventions as docs/design.md: pose of cam1 in the world (d_j, R_j); camera k at D_k, R_k.
 */
#ifndef RP_RENDER_HPP
#define RP_RENDER_HPP

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "rigpose/rp_rig.h"
#include "rigpose/rp_track.h"
#include "rp_sim.h"
#include "../common/rp_cv.hpp"
#include "rp_noise.hpp"

namespace rpr {

/* A bright Gaussian spot painted on the surface (for tests): centre direction u (any length),
 * angular sigma (rad), amplitude added to the albedo (grey levels / 255). */
struct Marker {
    double u[3];
    double sigma_rad;
    double amp;
};

struct SceneCfg {
    uint64_t seed = 1;
    double r_mid = 0.8335;  /* m: the shell's mid radius (0.667 + 1) / 2 */
    double r_amp = 0.1665;  /* m: radii span r_mid +- r_amp */
    int face_px = 1024;     /* albedo cube map face side, texels (1.6 mm at r_mid) */
    int radius_face_px = 96; /* radius cube map face side, texels */
    bool plain = false;     /* uniform grey albedo (0.2): with markers, for geometry tests */
    std::vector<Marker> markers;
};

/* A float cube map: 6 faces of n x n texels plus a border of `pad` on every side. */
class CubeMap {
public:
    void init(int n, int pad);
    /* Fill every texel (border included) with f(unit direction). */
    template <class F> void fill(F f);
    /* Bilinear value in direction u (need not be unit; must be non-zero). */
    float at(const double u[3]) const;
    /* Texel (face, i, j) -> unit direction (i, j may lie in the border). */
    void texel_dir(int face, int i, int j, double u[3]) const;

private:
    int n_ = 0, pad_ = 0, side_ = 0;
    std::vector<float> v_;
    friend class Scene;
};

class Scene {
public:
    /* Builds the cube maps (a few seconds at the default size; uses cv::parallel_for_). */
    explicit Scene(const SceneCfg &cfg);
    const SceneCfg &cfg() const { return cfg_; }
    /* Surface radius (m) in direction u. */
    double radius(const double u[3]) const { return radius_.at(u); }
    /* Albedo (0..1, may exceed slightly with markers) in direction u. */
    float albedo(const double u[3]) const { return albedo_.at(u); }
    /* The surface point in direction u: r(u) u/|u| (world, m). */
    void surface_point(const double u[3], double M[3]) const;
    /* Ray C + t d (d unit, C inside the surface) against the surface: t > 0 (m) and the hit's
     * direction from the origin (unit). false if C is not inside or the iteration failed. */
    bool intersect(const double C[3], const double d[3], double *t, double u_hit[3]) const;

private:
    SceneCfg cfg_;
    CubeMap radius_, albedo_;
};

/* Scene "points": the feature-level simulation's own point cloud made visible. Each point (the
 * run's 10,000 points of rp_sim_run_init, at the same places) carries a flat disc of radius
 * radius_m facing the world origin (the rig's start, so every camera sees it nearly face-on):
 * a grey body level away from the background plus gradient noise in the disc's plane (two
 * octaves, wavelengths kWave0 and kWave0 / 2; each disc its own patch of the noise field), the
 * corners a tracker finds; opaque to 0.7 radii and fading smoothly to transparent at the rim. Rendering paints
 * the discs of a camera back to front (centre depth) with alpha over a uniform background; a
 * sub-pixel's value is the disc's albedo where its ray crosses the disc's plane (exact, no
 * texture maps). A tracked corner is a physical point within radius_m of one of rp_sim's
 * points, so the scene's depths per view are the simulation's. */
struct DiscCfg {
    double radius_m = 0.012;  /* 11.5 px at the shell's mid radius with fx = 800 */
    float background = 0.5f;  /* albedo where no disc is hit */
    uint64_t seed = 1;        /* body levels and spots */
};

struct CamRays;
struct ObjView;

class DiscScene {
public:
    static constexpr int kOctaves = 2;
    static constexpr double kWave0 = 0.67; /* first wavelength, disc radii */
    static constexpr double kAmp0 = 0.45;   /* albedo amplitude of the first octave */
    /* centres: n x 3 world metres. */
    DiscScene(const std::vector<double> &centres, const DiscCfg &cfg);
    size_t size() const { return discs_.size(); }
    const double *centre(size_t i) const;
    const DiscCfg &cfg() const { return cfg_; }
    /* Disc i's normal (towards the world origin) and in-plane axes, world, unit. */
    void axes(size_t i, double n[3], double e1[3], double e2[3]) const;
    /* Albedo (0..1) and opacity (0..1) of disc i at (a, b) metres from its centre in its plane. */
    void look(size_t i, double a, double b, float *albedo, float *alpha) const;
    /* The nearest disc that ray C + t d (world, d need not be unit) crosses where it is at
     * least half opaque: its index and the crossing point X (world). false if none. For ground
     * truth of tracked features (a brute-force search over all discs). */
    bool pick(const double C[3], const double d[3], size_t *idx, double X[3]) const;
    /* As render_albedo: the albedo image of rig camera k at pose (d, R); ov: a moving object
     * in front (optional). */
    void render(const rp_rig_t &rig, int k, const double d[3], const double R[9],
                const CamRays &rays, cv::Mat *out, const ObjView *ov = nullptr) const;

private:
    struct Disc {
        double c[3], n[3], e1[3], e2[3]; /* centre, normal, in-plane axes (world) */
        float level;
        float off[3];                    /* the disc's offset in the noise field */
    };
    DiscCfg cfg_;
    GradNoise noise_;
    std::vector<Disc> discs_;
};

/* A moving object as one camera sees it in one frame: a textured sphere of radius `radius` (m)
 * centred at c (camera frame, m), its axes Q (columns, camera frame, row-major). A sub-pixel
 * sample whose ray meets it takes the object's albedo at the hit (the object is always nearer
 * than the scene: it stays inside the shell's inner radius, see MovingObject). */
class MovingObject;
struct ObjView {
    const MovingObject *obj = nullptr;
    double c[3] = {0, 0, 0};
    double Q[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double radius = 0.0;
    /* Ray (camera frame, unit) against the sphere: distance t (m) to the nearer hit. */
    bool hit_t(const float r[3], double *t) const;
    /* The object's albedo where ray r meets it at distance t. */
    float albedo_at(const float r[3], double t) const;
};

/* Per-camera rays: for each pixel (row-major) ss x ss sub-pixel rays in the camera frame
 * (unit vectors, float), from rp_cam_unproject. Sub-pixel (a, b) of pixel (u, v) sits at
 * (u - 0.5 + (a + 0.5) / ss, v - 0.5 + (b + 0.5) / ss). */
struct CamRays {
    int w = 0, h = 0, ss = 1;
    std::vector<float> ray; /* (h * w * ss * ss) x 3 */
    int n_fail = 0;         /* sub-pixels with no valid ray (distortion folds): rendered black */
};
bool make_rays(const rp_camera_t &cam, int ss, CamRays *out);

/* Rig camera k in the world at rig pose (d, R) (cam1 in the world; row-major): its centre
 * C = d + R D_k and axes M = R R_k (columns; row-major). */
void cam_in_world(const rp_rig_t &rig, int k, const double d[3], const double R[9], double C[3],
                  double M[9]);

/* Image of rig camera k at pose (d, R) (cam1 in the world; R row-major): a CV_32F image of
 * albedo values (0..1); pixels whose ray misses are 0. */
void render_albedo(const Scene &scene, const rp_rig_t &rig, int k, const double d[3],
                   const double R[9], const CamRays &rays, cv::Mat *out,
                   const ObjView *ov = nullptr);

/* An independently moving textured object (rigpose-render --moving-object): a sphere whose
 * radius makes it cover `cover` of camera `cam`'s image when centred in it at `depth` (m). Its
 * path is set in that camera's frame, so that it stays in view whatever the rig does: its centre
 * at (x(t), y(t), depth), x and y single sinusoids (periods U[3, 5] s and U[2, 4] s, random
 * phases, amplitudes 0.6 of the room the image leaves around the object), the sphere spinning at
 * 0.6 rad/s about a random axis. In the world it moves with the camera plus that drift and spin:
 * like a vehicle alongside, its image motion agrees neither with the static scene nor with the
 * rig. Its albedo is the scene's kind of texture (gradient noise and stains, rp_render.cpp),
 * scaled by r_mid / depth so that it has the scene's scale in pixels. Deterministic per seed. */
struct ObjectCfg {
    uint64_t seed = 1;
    int cam = 0;          /* rig camera whose view it covers */
    double cover = 0.30;  /* fraction of that camera's image (when centred) */
    double depth = 0.45;  /* m, along that camera's axis */
};

class MovingObject {
public:
    MovingObject(const ObjectCfg &cfg, const rp_camera_t &cam);
    const ObjectCfg &cfg() const { return cfg_; }
    double radius() const { return radius_; }
    /* Centre p (m) and axes Q (columns, row-major) in the chosen camera's frame at time t (s). */
    void rel_pose(double t, double p[3], double Q[9]) const;
    /* Albedo (0..1) at point x (m) of the object's own frame, |x| = radius. */
    float albedo(const double x[3]) const;

private:
    ObjectCfg cfg_;
    double radius_ = 0.0;
    double amp_[2] = {0, 0}, w_[2] = {0, 0}, ph_[2] = {0, 0};
    double axis_[3] = {0, 0, 1}, spin_ = 0.6, Q0_[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double tex_scale_ = 1.0;
    GradNoise base_, stain1_, stain2_;
};

/* Image degradations, all optional, applied to the albedo image in this order:
 * gain (brightness change) and offset, Gaussian blur, Gaussian grey-level noise, rounding to
 * 8 bits with saturation. The noise is a function of noise_key only. */
struct Effects {
    double gain = 1.0;        /* multiplies the albedo (x 255) */
    double offset = 0.0;      /* grey levels added */
    double blur_sigma = 0.0;  /* px; 0 = none */
    double noise_grey = 0.0;  /* sigma, grey levels; 0 = none */
    uint64_t noise_key = 0;
};
void finish_image(const cv::Mat &albedo, const Effects &fx, cv::Mat *out8);

/* The rig pose of a frame as docs/design.md: translation and rotation matrix (double). */
struct Pose {
    double d[3];
    double R[9];
};

/* A cv::Mat (CV_8U, one channel) as the core's rp_image_t (borrowed: the Mat must outlive it). */
inline rp_image_t image_view(const cv::Mat &m)
{
    return rp_cv_view(m);
}

/* splitmix64 mixing of a few integers into one key (for per-frame, per-camera streams). */
uint64_t key(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0);

/* A rendered run of the paper's protocol: the six-camera rig of rp_sim_make_rig (with the given
 * intrinsics and distortion), the trajectory of run `run` of the experiment seeded by `seed`
 * (rp_sim_run_init: the same motion as rigpose-sim's run), a shell scene seeded by (seed, run),
 * or (points) that run's own point cloud as discs. */
struct SeqCfg {
    int width = 640, height = 480;
    double focal_px = 0.0;       /* 0: 800 x width / 640 (the protocol's 800 px at 640x480) */
    double dist[5] = {0, 0, 0, 0, 0}; /* k1 k2 p1 p2 k3 of every camera */
    int ss = 2;                  /* sub-pixel samples per axis */
    uint32_t frames = 100;
    uint64_t seed = 1;
    uint32_t run = 0;
    double noise_grey = 1.0;     /* image noise sigma, grey levels */
    double blur_sigma = 0.0;     /* px */
    double brightness = 0.0;     /* gain amplitude: gain_j,k = 1 + b sin(2 pi j / 40 + k) */
    bool flat = false;           /* sphere of radius r_mid instead of the bumpy shell */
    bool points = false;         /* the "points" scene (DiscScene) instead of the shell */
    double disc_radius = 0.012;  /* m, points scene */
    int face_px = 1024;
    int motion = 0;              /* rp_sim_motion_t: 0 the paper's, 1 turn, 2 pitch, 3 smooth
                                  * (rp_sim.h) */
    /* Camera clocks (rp_sim.h; a continuous motion only): per rig camera its unknown offset (s)
     * and the Gaussian jitter (s) of every capture time. Each image is rendered at its camera's
     * true capture time (set time + offset + jitter) and stamped with the set's time. */
    double cam_offset_s[RP_SIM_NCAMS] = {0, 0, 0, 0, 0, 0};
    double jitter_s = 0.0;
    bool moving_object = false;  /* an independently moving object (MovingObject) */
    int object_cam = 0;          /* the rig camera whose view it covers */
    double object_cover = 0.30;  /* the fraction of that view it covers */
};

class Sequence {
public:
    /* ok() is false if the configuration is unusable (why() says what). */
    explicit Sequence(const SeqCfg &cfg);
    bool ok() const { return why_.empty(); }
    const std::string &why() const { return why_; }
    const SeqCfg &cfg() const { return cfg_; }
    const rp_rig_t &rig() const { return rig_; }
    /* The shell scene; only when !points() (the points scene has no surface). */
    const Scene &scene() const { return *scene_; }
    bool points() const { return discs_ != nullptr; }
    /* The points scene's disc centres (= rp_sim's points of this run), n x 3; empty for the shell. */
    const std::vector<double> &point_cloud() const { return cloud_; }
    /* The points scene (only when points()). */
    const DiscScene &discs() const { return *discs_; }
    /* The world point seen at pixel uv of rig camera k at frame j: where the pixel's ray meets
     * the shell, or (points scene) the nearest half-opaque disc on it. false if none. */
    bool world_point_at(uint32_t j, int k, const rp_real uv[2], double X[3]) const;
    /* Truth of frame j: [tx ty tz alpha beta gamma] (as rp_estimate_t.p) and the pose. */
    const double *truth(uint32_t j) const { return &truth_[6u * j]; }
    Pose pose(uint32_t j) const;
    /* The pose at rig camera k's capture time in frame set j: pose(j) without clocks, else the
     * pose at the set's time + the camera's offset + its jitter (rp_sim_cam_frame). Images,
     * world_point_at and the moving object's view use it. */
    Pose cam_pose(uint32_t j, int k) const;
    /* true when camera clocks are set (cam_pose differs from pose) */
    bool clocked() const { return !cam_d_.empty(); }
    int64_t utime(uint32_t j) const;
    /* 8-bit image of rig camera k at frame j, with the configured degradations. */
    void render(uint32_t j, int k, cv::Mat *out8) const;
    /* The moving object as rig camera k sees it at frame j (false: no object). */
    bool object_view(uint32_t j, int k, ObjView *ov) const;
    /* The moving object's centre (world, m) at frame j; only with cfg().moving_object. */
    const double *object_centre(uint32_t j) const { return &obj_c_[3u * j]; }
    const MovingObject *object() const { return object_.get(); }

private:
    SeqCfg cfg_;
    std::string why_;
    rp_rig_t rig_;
    std::vector<double> truth_, truth_R_;
    std::vector<double> cam_d_, cam_R_; /* with clocks: per set and camera, 3 and 9 (cam_pose) */
    double frame_dt_ = 1.0 / 30.0;
    std::unique_ptr<Scene> scene_;
    std::unique_ptr<DiscScene> discs_;
    std::vector<double> cloud_;
    std::vector<CamRays> rays_;
    std::unique_ptr<MovingObject> object_;
    std::vector<double> obj_c_, obj_Q_; /* per frame: centre and axes in the world */
};

/* The feature-level simulation's model on the rendered surface (a reference for runs from
 * pixels with the scene's own depths): n points on the surface in directions uniform over the
 * sphere (seeded by seed_key); world metres, 3 per point. */
std::vector<double> surface_points(const Scene &scene, int n, uint64_t seed_key);

/* Frame set of frame j of seq from points pts, as rp_sim_frame makes it (with clocks, each camera
 * from its own cam_pose, stamped with the set's time): in each of the first
 * n_cams rig cameras every point at least 0.05 m in front that projects inside the image
 * (the first RP_MAX_FEATS_PER_CAM of them), id = point index, plus independent Gaussian noise
 * of noise_px per coordinate (seeded by noise_key, j and the camera). */
void surface_features(const Sequence &seq, const std::vector<double> &pts, int n_cams,
                      uint32_t j, double noise_px, uint64_t noise_key, rp_frameset_t *fs);

} /* namespace rpr */

#endif /* RP_RENDER_HPP */
