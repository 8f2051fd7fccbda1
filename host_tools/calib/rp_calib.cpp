/*
 * rp_calib.cpp - see rp_calib.hpp.
 */
#include "rp_calib.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rpc {

std::vector<cv::Point3f> Board::object_points() const
{
    std::vector<cv::Point3f> p;
    for (int r = 0; r < inner.height; ++r) {
        for (int c = 0; c < inner.width; ++c) {
            p.emplace_back(static_cast<float>(c * square_m), static_cast<float>(r * square_m), 0.f);
        }
    }
    return p;
}

Pose Pose::inv() const
{
    Pose o;
    o.R = R.t();
    o.t = -(o.R * t);
    return o;
}

Pose Pose::operator*(const Pose &b) const
{
    Pose o;
    o.R = R * b.R;
    o.t = R * b.t + t;
    return o;
}

static Pose pose_from_rt(const cv::Mat &rvec, const cv::Mat &tvec)
{
    Pose p;
    cv::Mat R;
    cv::Rodrigues(rvec, R);
    p.R = cv::Matx33d(R);
    p.t = cv::Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
    return p;
}

View detect_board(const std::string &file, const Board &board, cv::Size *size)
{
    View v;
    v.file = file;
    cv::Mat img;
    try {
        img = cv::imread(file, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception &e) {
        v.why = std::string("unreadable: ") + e.what();
        return v;
    }
    if (img.empty()) {
        v.why = "unreadable, corrupt or not an image";
        return v;
    }
    if (!size->empty() && img.size() != *size) {
        char b[128];
        std::snprintf(b, sizeof b, "image is %dx%d, the camera's first image was %dx%d", img.cols,
                      img.rows, size->width, size->height);
        v.why = b;
        return v;
    }
    try {
        const int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE |
                          cv::CALIB_CB_FAST_CHECK;
        if (!cv::findChessboardCorners(img, board.inner, v.corners, flags)) {
            char b[96];
            std::snprintf(b, sizeof b, "no %dx%d chessboard found", board.inner.width,
                          board.inner.height);
            v.why = b;
            v.corners.clear();
            return v;
        }
        cv::cornerSubPix(img, v.corners, cv::Size(11, 11), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1));
    } catch (const cv::Exception &e) {
        v.why = std::string("corner detection failed: ") + e.what();
        v.corners.clear();
        return v;
    }
    if (size->empty()) {
        *size = img.size();
    }
    v.found = true;
    return v;
}

bool calibrate_intrinsics(const std::vector<View> &views, const Board &board, cv::Size size,
                          const IntrinsicsOpts &opts, Intrinsics *out, std::string *why)
{
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> img;
    Intrinsics r;
    r.size = size;
    for (size_t i = 0; i < views.size(); ++i) {
        if (views[i].found) {
            obj.push_back(board.object_points());
            img.push_back(views[i].corners);
            r.used.push_back(static_cast<int>(i));
        }
    }
    if (img.size() < 3) {
        *why = "fewer than 3 views with the board (" + std::to_string(img.size()) + ")";
        return false;
    }
    int flags = 0;
    if (opts.fix_aspect) {
        flags |= cv::CALIB_FIX_ASPECT_RATIO;
    }
    if (opts.zero_tangential) {
        flags |= cv::CALIB_ZERO_TANGENT_DIST;
    }
    cv::Mat K = cv::Mat::eye(3, 3, CV_64F), D;
    std::vector<cv::Mat> rv, tv;
    try {
        if (opts.fixed) {
            if (opts.fixed->size != size) {
                *why = "the given intrinsics are for another image size";
                return false;
            }
            K = cv::Mat(opts.fixed->K).clone();
            D = cv::Mat(opts.fixed->dist).clone();
            double s2 = 0.0;
            for (size_t i = 0; i < img.size(); ++i) {
                cv::Mat r1, t1;
                cv::solvePnP(obj[i], img[i], K, D, r1, t1);
                rv.push_back(r1);
                tv.push_back(t1);
                std::vector<cv::Point2f> proj;
                cv::projectPoints(obj[i], r1, t1, K, D, proj);
                for (size_t j = 0; j < proj.size(); ++j) {
                    const cv::Point2f d = proj[j] - img[i][j];
                    s2 += static_cast<double>(d.dot(d));
                }
            }
            r.rms_px = std::sqrt(s2 / static_cast<double>(img.size() * obj[0].size()));
        } else {
            r.rms_px = cv::calibrateCamera(obj, img, size, K, D, rv, tv, flags);
        }
    } catch (const cv::Exception &e) {
        *why = std::string("calibrateCamera failed: ") + e.what();
        return false;
    }
    if (!std::isfinite(r.rms_px) || !cv::checkRange(K) || !cv::checkRange(D)) {
        *why = "calibration diverged (non-finite result)";
        return false;
    }
    r.K = cv::Matx33d(K);
    for (int i = 0; i < 5 && i < static_cast<int>(D.total()); ++i) {
        r.dist[static_cast<size_t>(i)] = D.at<double>(i);
    }
    for (size_t i = 0; i < img.size(); ++i) {
        std::vector<cv::Point2f> proj;
        cv::projectPoints(obj[i], rv[i], tv[i], K, D, proj);
        double s = 0.0;
        for (size_t j = 0; j < proj.size(); ++j) {
            const cv::Point2f d = proj[j] - img[i][j];
            s += static_cast<double>(d.dot(d));
        }
        r.view_rms_px.push_back(std::sqrt(s / static_cast<double>(proj.size())));
        r.board_in_cam.push_back(pose_from_rt(rv[i], tv[i]));
    }
    *out = r;
    return true;
}

bool calibrate_stereo(const std::vector<View> &left, const std::vector<View> &right,
                      const Board &board, const Intrinsics &kl, const Intrinsics &kr,
                      Stereo *out, std::string *why)
{
    if (left.size() != right.size()) {
        *why = "left and right view lists differ in length";
        return false;
    }
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> il, ir;
    Stereo s;
    for (size_t i = 0; i < left.size(); ++i) {
        if (!left[i].found || !right[i].found) {
            continue;
        }
        obj.push_back(board.object_points());
        il.push_back(left[i].corners);
        ir.push_back(right[i].corners);
        /* this pair's own estimate of the right camera's pose relative to the left one */
        Pose pl, pr;
        cv::Mat rv, tv;
        cv::solvePnP(obj.back(), il.back(), cv::Mat(kl.K), kl.dist, rv, tv);
        pl = pose_from_rt(rv, tv);
        cv::solvePnP(obj.back(), ir.back(), cv::Mat(kr.K), kr.dist, rv, tv);
        pr = pose_from_rt(rv, tv);
        s.pair_baseline_m.push_back(cv::norm((pr * pl.inv()).t));
    }
    s.n_pairs = static_cast<int>(obj.size());
    if (s.n_pairs < 3) {
        *why = "fewer than 3 pairs with the board in both images (" + std::to_string(s.n_pairs) + ")";
        return false;
    }
    cv::Mat K1(kl.K), K2(kr.K), R, T, E, F;
    try {
        s.rms_px = cv::stereoCalibrate(obj, il, ir, K1, kl.dist, K2, kr.dist, kl.size, R, T, E, F,
                                       cv::CALIB_FIX_INTRINSIC);
    } catch (const cv::Exception &e) {
        *why = std::string("stereoCalibrate failed: ") + e.what();
        return false;
    }
    s.left_in_right.R = cv::Matx33d(R);
    s.left_in_right.t = cv::Vec3d(T.at<double>(0), T.at<double>(1), T.at<double>(2));
    s.E = cv::Matx33d(E);
    s.F = cv::Matx33d(F);
    s.baseline_m = cv::norm(s.left_in_right.t);
    *out = s;
    return true;
}

bool hand_eye(const std::vector<Pose> &ref_board_in_cam, const std::vector<Pose> &k_board_in_cam,
              Pose *cam_k_in_ref, double *residual_rot_rad, double *residual_t_m, std::string *why)
{
    const size_t n = ref_board_in_cam.size();
    if (n != k_board_in_cam.size() || n < 3) {
        *why = "hand-eye needs at least 3 simultaneous board poses of both cameras";
        return false;
    }
    /* OpenCV's names: gripper = the reference camera (the rig), base = its static board,
     * camera = camera k, target = camera k's static board. cam2gripper is then camera k in the
     * reference camera's frame. */
    std::vector<cv::Mat> Rg2b, tg2b, Rt2c, tt2c;
    for (size_t i = 0; i < n; ++i) {
        const Pose g2b = ref_board_in_cam[i].inv();
        Rg2b.push_back(cv::Mat(g2b.R).clone());
        tg2b.push_back(cv::Mat(g2b.t).clone());
        Rt2c.push_back(cv::Mat(k_board_in_cam[i].R).clone());
        tt2c.push_back(cv::Mat(k_board_in_cam[i].t).clone());
    }
    cv::Mat R, t;
    try {
        cv::calibrateHandEye(Rg2b, tg2b, Rt2c, tt2c, R, t, cv::CALIB_HAND_EYE_PARK);
    } catch (const cv::Exception &e) {
        *why = std::string("calibrateHandEye failed: ") + e.what();
        return false;
    }
    if (!cv::checkRange(R) || !cv::checkRange(t)) {
        *why = "hand-eye diverged (degenerate motion: rotate the rig about two different axes)";
        return false;
    }
    Pose X;
    X.R = cv::Matx33d(R);
    X.t = cv::Vec3d(t.at<double>(0), t.at<double>(1), t.at<double>(2));
    /* Residual of A_i X = X B_i over consecutive sets: A_i = T_ref(i+1) T_ref(i)^-1 moves the
     * reference camera's coordinates from set i to i+1, B_i the same for camera k, X = camera k
     * in the reference camera (p_ref = X p_k). */
    double sr = 0.0, st = 0.0;
    for (size_t i = 0; i + 1 < n; ++i) {
        const Pose A = ref_board_in_cam[i + 1] * ref_board_in_cam[i].inv();
        const Pose B = k_board_in_cam[i + 1] * k_board_in_cam[i].inv();
        const Pose lhs = A * X, rhs = X * B;
        cv::Mat dr;
        cv::Rodrigues(cv::Mat(lhs.R * rhs.R.t()), dr);
        sr += cv::norm(dr) * cv::norm(dr);
        st += cv::norm(lhs.t - rhs.t) * cv::norm(lhs.t - rhs.t);
    }
    *residual_rot_rad = std::sqrt(sr / static_cast<double>(n - 1));
    *residual_t_m = std::sqrt(st / static_cast<double>(n - 1));
    *cam_k_in_ref = X;
    return true;
}

/* Pose from a 6-vector (Rodrigues rotation, translation). */
static Pose pose_from6(const double *v)
{
    Pose p;
    cv::Mat R;
    cv::Rodrigues(cv::Vec3d(v[0], v[1], v[2]), R);
    p.R = cv::Matx33d(R);
    p.t = cv::Vec3d(v[3], v[4], v[5]);
    return p;
}

static void pose_to6(const Pose &p, double *v)
{
    cv::Vec3d r;
    cv::Rodrigues(cv::Mat(p.R), r);
    for (int i = 0; i < 3; ++i) {
        v[i] = r[i];
        v[3 + i] = p.t[i];
    }
}

/* Reprojection residuals of one camera seeing the board at `board_in_cam`. */
static void reproj(const Pose &board_in_cam, const std::vector<cv::Point3f> &obj,
                   const std::vector<cv::Point2f> &px, const Intrinsics &k, double *out)
{
    cv::Vec3d rv;
    cv::Rodrigues(cv::Mat(board_in_cam.R), rv);
    std::vector<cv::Point2f> proj;
    cv::projectPoints(obj, rv, board_in_cam.t, cv::Mat(k.K), k.dist, proj);
    for (size_t j = 0; j < proj.size(); ++j) {
        out[2 * j] = static_cast<double>(proj[j].x - px[j].x);
        out[2 * j + 1] = static_cast<double>(proj[j].y - px[j].y);
    }
}

bool refine_extrinsics(const std::vector<std::vector<cv::Point2f>> &c_ref,
                       const std::vector<std::vector<cv::Point2f>> &c_k, const Intrinsics &k_ref,
                       const Intrinsics &k_k, const Board &board, Pose *cam_k_in_ref,
                       double *rms_px, std::string *why)
{
    const int n = static_cast<int>(c_ref.size());
    const std::vector<cv::Point3f> obj = board.object_points();
    const int m = static_cast<int>(obj.size());
    if (n < 3 || c_k.size() != c_ref.size()) {
        *why = "refinement needs at least 3 sets of both cameras";
        return false;
    }
    for (int i = 0; i < n; ++i) {
        if (static_cast<int>(c_ref[static_cast<size_t>(i)].size()) != m ||
            static_cast<int>(c_k[static_cast<size_t>(i)].size()) != m) {
            *why = "corner count differs from the board's";
            return false;
        }
    }
    /* parameters: [P_0 .. P_{n-1} (reference board in the reference camera), X, Y] */
    const int np = 6 * n + 12, nr = 4 * m; /* residuals per set */
    std::vector<double> p(static_cast<size_t>(np));
    const Pose X0 = *cam_k_in_ref;
    Pose Y0;
    for (int i = 0; i < n; ++i) {
        rpc::Pose P;
        cv::Mat rv, tv;
        cv::solvePnP(obj, c_ref[static_cast<size_t>(i)], cv::Mat(k_ref.K), k_ref.dist, rv, tv);
        P = pose_from_rt(rv, tv);
        pose_to6(P, &p[static_cast<size_t>(6 * i)]);
        if (i == 0) {
            cv::solvePnP(obj, c_k[0], cv::Mat(k_k.K), k_k.dist, rv, tv);
            Y0 = P.inv() * X0 * pose_from_rt(rv, tv); /* camera k's board in the reference board */
        }
    }
    pose_to6(X0, &p[static_cast<size_t>(6 * n)]);
    pose_to6(Y0, &p[static_cast<size_t>(6 * n + 6)]);
    auto set_res = [&](const std::vector<double> &q, int i, double *out) {
        const Pose P = pose_from6(&q[static_cast<size_t>(6 * i)]);
        const Pose X = pose_from6(&q[static_cast<size_t>(6 * n)]);
        const Pose Y = pose_from6(&q[static_cast<size_t>(6 * n + 6)]);
        reproj(P, obj, c_ref[static_cast<size_t>(i)], k_ref, out);
        reproj(X.inv() * P * Y, obj, c_k[static_cast<size_t>(i)], k_k, out + 2 * m);
    };
    auto all_res = [&](const std::vector<double> &q, cv::Mat *r) {
        *r = cv::Mat(n * nr, 1, CV_64F);
        for (int i = 0; i < n; ++i) {
            set_res(q, i, r->ptr<double>(i * nr));
        }
        return r->dot(*r);
    };
    cv::Mat r;
    double cost = all_res(p, &r), lambda = 1e-3;
    const double cost0 = cost;
    for (int it = 0; it < 50; ++it) {
        cv::Mat J = cv::Mat::zeros(n * nr, np, CV_64F);
        std::vector<double> rp(static_cast<size_t>(nr)), rm(static_cast<size_t>(nr));
        for (int j = 0; j < np; ++j) {
            const double h = 1e-6;
            const int i0 = j < 6 * n ? j / 6 : 0, i1 = j < 6 * n ? j / 6 + 1 : n;
            std::vector<double> qp = p, qm = p;
            qp[static_cast<size_t>(j)] += h;
            qm[static_cast<size_t>(j)] -= h;
            for (int i = i0; i < i1; ++i) {
                set_res(qp, i, rp.data());
                set_res(qm, i, rm.data());
                for (int k = 0; k < nr; ++k) {
                    J.at<double>(i * nr + k, j) = (rp[static_cast<size_t>(k)] -
                                                   rm[static_cast<size_t>(k)]) / (2.0 * h);
                }
            }
        }
        const cv::Mat H = J.t() * J, g = J.t() * r;
        bool improved = false;
        for (int tries = 0; tries < 10 && !improved; ++tries) {
            cv::Mat Hd = H.clone(), dx;
            for (int j = 0; j < np; ++j) {
                Hd.at<double>(j, j) *= 1.0 + lambda;
            }
            if (!cv::solve(Hd, -g, dx, cv::DECOMP_CHOLESKY)) {
                lambda *= 10.0;
                continue;
            }
            std::vector<double> q = p;
            for (int j = 0; j < np; ++j) {
                q[static_cast<size_t>(j)] += dx.at<double>(j);
            }
            cv::Mat r2;
            const double c2 = all_res(q, &r2);
            if (std::isfinite(c2) && c2 < cost) {
                improved = true;
                const bool converged = cost - c2 < 1e-10 * cost;
                p = q;
                r = r2;
                cost = c2;
                lambda = std::max(lambda / 10.0, 1e-9);
                if (converged) {
                    it = 1000;
                }
            } else {
                lambda *= 10.0;
            }
        }
        if (!improved) {
            break;
        }
    }
    if (!std::isfinite(cost) || cost > cost0) {
        *why = "bundle adjustment diverged";
        return false;
    }
    *cam_k_in_ref = pose_from6(&p[static_cast<size_t>(6 * n)]);
    *rms_px = std::sqrt(cost / (2.0 * n * m)); /* per corner (Euclidean), both cameras */
    return true;
}

static void put_list(FILE *f, const char *key, const double *v, int n, const char *fmt)
{
    std::fprintf(f, "    %s: [", key);
    for (int i = 0; i < n; ++i) {
        std::fprintf(f, fmt, v[i]);
        std::fprintf(f, "%s", i + 1 < n ? ", " : "]\n");
    }
}

bool write_config(const std::string &path, const std::vector<CamOut> &cams,
                  const std::vector<std::pair<int, int>> &pairs, const std::string &source_kind,
                  const std::string &replay_index, const std::string &meta_note,
                  std::string *why)
{
    if (cams.empty() || cams.size() > 6) {
        *why = "a configuration holds 1..6 cameras";
        return false;
    }
    FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        *why = "cannot write " + path;
        return false;
    }
    std::time_t now = std::time(nullptr);
    char date[32];
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    std::fprintf(f, "# rigpose configuration written by rigpose-calib (schema: config/README.md)\n"
                    "version: 1\n\nmeta:\n  tool: rigpose-calib\n  date: \"%s\"\n", date);
    if (!meta_note.empty()) {
        std::fprintf(f, "  note: \"%s\"\n", meta_note.c_str());
    }
    std::fprintf(f, "  rms_px: {");
    for (size_t i = 0; i < cams.size(); ++i) {
        std::fprintf(f, "%s: %.4f%s", cams[i].name.c_str(), cams[i].intr.rms_px,
                     i + 1 < cams.size() ? ", " : "}\n");
    }
    std::fprintf(f, "\nsource:\n  kind: %s\n", source_kind.c_str());
    if (source_kind == "replay") {
        std::fprintf(f, "  replay_index: \"%s\"\n", replay_index.c_str());
    }
    std::fprintf(f, "\ncameras:\n");
    for (size_t i = 0; i < cams.size(); ++i) {
        const CamOut &c = cams[i];
        const double in[4] = {c.intr.K(0, 0), c.intr.K(1, 1), c.intr.K(0, 2), c.intr.K(1, 2)};
        Pose p = c.in_cam1;
        if (i == 0) {
            p = Pose(); /* the reference, exactly */
        }
        double R[9], D[3];
        for (int r = 0; r < 3; ++r) {
            D[r] = p.t[r];
            for (int q = 0; q < 3; ++q) {
                R[3 * r + q] = p.R(r, q);
            }
        }
        std::fprintf(f, "  - name: %s\n    device: \"%s\"\n    width: %d\n    height: %d\n",
                     c.name.c_str(), c.device.c_str(), c.intr.size.width, c.intr.size.height);
        put_list(f, "intrinsics", in, 4, "%.6f");
        put_list(f, "distortion", c.intr.dist.data(), 5, "%.9g");
        put_list(f, "position", D, 3, "%.9f");
        put_list(f, "rotation", R, 9, "%.12f");
    }
    std::fprintf(f, "\nestimator:\n");
    if (pairs.size() == 2 || pairs.size() == 1) {
        std::fprintf(f, "  method: %s\n  pairs: [", pairs.size() == 2 ? "stereo4" : "stereo2");
        for (size_t i = 0; i < pairs.size(); ++i) {
            std::fprintf(f, "[%s, %s]%s", cams[static_cast<size_t>(pairs[i].first)].name.c_str(),
                         cams[static_cast<size_t>(pairs[i].second)].name.c_str(),
                         i + 1 < pairs.size() ? ", " : "]\n");
        }
    } else {
        std::fprintf(f, "  method: gc\n  cams: [");
        for (size_t i = 0; i < cams.size(); ++i) {
            std::fprintf(f, "%s%s", cams[i].name.c_str(), i + 1 < cams.size() ? ", " : "]\n");
        }
    }
    const bool ok = std::fclose(f) == 0;
    if (!ok) {
        *why = "write error on " + path;
    }
    return ok;
}

} // namespace rpc
