/*
 * rigpose-log - records synchronised frame sets from the rig through the platform HAL (the
 * source of a rigpose configuration file: v4l2 or replay), with the rigpose daemon's poses, and
 * turns recordings back into something the daemon replays.
 *
 *   rigpose-log record --config FILE [--dir DIR] [--log FILE.log] [--frames N] [--fast]
 *                      [--listen URL] [--pose-channel NAME] [--status-channel NAME]
 *                      [--linger-ms MS] [--image-channel NAME]
 *       every frame set: into DIR as a replay folder (camK/NNNNNN.pgm, frames.csv, truth.csv when
 *       the source knows the truth, rig.yaml = FILE with a replay source) and / or into an LCM
 *       log as rigpose.image_t messages (one per camera, channel RIGPOSE_IMAGE), which
 *       lcm-logplayer replays. --listen URL also writes into the log every rigpose.pose_t /
 *       status_t the daemon publishes there (channels of FILE's lcm section unless given), until
 *       the daemon has been quiet for --linger-ms (500) after the last set.
 *   rigpose-log replay FILE.log --dir DIR [--config FILE] [--image-channel NAME] [--tolerant]
 *       an LCM log's images back into a replay folder for the daemon (`rigpose --config
 *       DIR/rig.yaml`, written when --config gives the rig). The log is read by
 *       host_tools/common/rp_lcmlog.h: a truncated or corrupt log is refused with one line
 *       "FILE: offset N: what" and nothing is written; --tolerant reads on past bad stretches
 *       (one warning line per skip: offset and bytes skipped).
 *   rigpose-log mcap FILE.log OUT.mcap [--config FILE] [rigpose-view options]
 *       an LCM log (poses, status, images) into an MCAP file that opens in Foxglove with the
 *       live view's topics and layout: runs `rigpose-view --lcm-log FILE.log --mcap OUT.mcap`,
 *       the rigpose-view installed beside this program (host_tools/view/).
 *
 * Recording prints progress every second (sets, rate, driver drops, missing cameras, lost sets)
 * and a summary; nothing is lost silently: a set the source could not deliver (timeout, unreadable
 * image) or the recorder could not write is counted as lost and said with its reason, a camera
 * missing from a set is counted and its image column left empty. SIGINT / SIGTERM stop cleanly.
 * Exit: 0 every set recorded, 1 some sets were lost (replay: or the log is truncated / corrupt),
 * 2 usage / configuration, 3 source or output could not be opened.
 */
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/eventlog.h>
#include <lcm/lcm.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_hal.h"
#include "rigpose_image_t.h"
#include "rp_lcm_image.h"
#include "rp_lcmlog.h"

namespace {

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-log record --config FILE [--dir DIR] [--log FILE.log] [--frames N]\n"
                 "                          [--fast] [--listen URL] [--pose-channel NAME]\n"
                 "                          [--status-channel NAME] [--linger-ms MS] [--image-channel NAME]\n"
                 "       rigpose-log replay FILE.log --dir DIR [--config FILE] [--image-channel NAME]\n"
                 "                          [--tolerant]\n"
                 "       rigpose-log mcap FILE.log OUT.mcap [--config FILE] [rigpose-view options]\n");
}

bool make_dir(const std::string &d)
{
    return mkdir(d.c_str(), 0777) == 0 || errno == EEXIST;
}

/* Binary PGM (P5), the replay source's lightest format. */
bool write_pgm(const std::string &path, const uint8_t *data, int w, int h, uint32_t stride)
{
    FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) {
        return false;
    }
    bool ok = std::fprintf(f, "P5\n%d %d\n255\n", w, h) > 0;
    for (int y = 0; ok && y < h; ++y) {
        ok = std::fwrite(data + static_cast<size_t>(y) * stride, 1, static_cast<size_t>(w), f) ==
             static_cast<size_t>(w);
    }
    return std::fclose(f) == 0 && ok;
}

/* The configuration text with its source replaced by the replay folder's and each camera's
 * device by its column (camK): the daemon's configuration of the recording. Works on the block
 * style our files use (top-level keys at column 0, one `device:` per camera). */
bool write_rig_yaml(const std::string &config, const std::string &out, int n_cams)
{
    std::ifstream in(config);
    if (!in) {
        return false;
    }
    std::ostringstream o;
    std::string line;
    bool in_source = false;
    int dev = 0;
    o << "# " << config << " as recorded by rigpose-log: replay source, devices = columns\n";
    while (std::getline(in, line)) {
        const bool top = !line.empty() && line[0] != ' ' && line[0] != '#' && line[0] != '-';
        if (top) {
            in_source = line.compare(0, 7, "source:") == 0;
            if (in_source) {
                o << "source:\n  kind: replay\n  replay_index: frames.csv\n  realtime: false\n";
                continue;
            }
        }
        if (in_source) {
            continue;
        }
        const size_t k = line.find("device:");
        if (k != std::string::npos && line.find_first_not_of(" -") == k && dev < n_cams) {
            o << line.substr(0, k) << "device: cam" << dev++ << "\n";
            continue;
        }
        o << line << "\n";
    }
    std::ofstream f(out);
    f << o.str();
    return static_cast<bool>(f) && dev == n_cams;
}

/* A replay folder being written. */
struct Folder {
    std::string dir;
    FILE *frames = nullptr, *truth = nullptr;
    int n_cams = 0;
    bool want_truth = false;

    bool open(const std::string &d, int n, bool with_truth, std::string *why)
    {
        dir = d;
        n_cams = n;
        if (!make_dir(dir)) {
            *why = "cannot create " + dir + ": " + std::strerror(errno);
            return false;
        }
        for (int k = 0; k < n; ++k) {
            if (!make_dir(dir + "/cam" + std::to_string(k))) {
                *why = "cannot create " + dir + "/cam" + std::to_string(k);
                return false;
            }
        }
        frames = std::fopen((dir + "/frames.csv").c_str(), "w");
        if (!frames) {
            *why = "cannot write " + dir + "/frames.csv";
            return false;
        }
        std::fprintf(frames, "utime_us");
        for (int k = 0; k < n; ++k) {
            std::fprintf(frames, ",cam%d", k);
        }
        std::fprintf(frames, "\n");
        want_truth = with_truth;
        return true;
    }

    /* One set: images[k] may be NULL (missing camera: empty column). */
    bool add(int64_t utime, uint32_t seq, const std::vector<const rp_image_t *> &images,
             const double *truth6, std::string *why)
    {
        std::string row = std::to_string(utime);
        char name[32];
        std::snprintf(name, sizeof name, "%06u.pgm", seq);
        for (int k = 0; k < n_cams; ++k) {
            row += ",";
            const rp_image_t *im = images[static_cast<size_t>(k)];
            if (!im) {
                continue;
            }
            const std::string rel = "cam" + std::to_string(k) + "/" + name;
            if (!write_pgm(dir + "/" + rel, im->data, im->w, im->h, im->stride)) {
                *why = "cannot write " + dir + "/" + rel + ": " + std::strerror(errno);
                return false;
            }
            row += rel;
        }
        if (std::fprintf(frames, "%s\n", row.c_str()) < 0 || std::fflush(frames) != 0) {
            *why = "cannot write " + dir + "/frames.csv";
            return false;
        }
        if (want_truth && truth6 && !truth) { /* created with the first set that has truth */
            truth = std::fopen((dir + "/truth.csv").c_str(), "w");
            if (!truth) {
                *why = "cannot write " + dir + "/truth.csv";
                return false;
            }
            std::fprintf(truth, "utime_us,tx,ty,tz,alpha,beta,gamma\n");
        }
        if (truth && truth6) {
            std::fprintf(truth, "%" PRId64 ",%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", utime, truth6[0],
                         truth6[1], truth6[2], truth6[3], truth6[4], truth6[5]);
        }
        return true;
    }

    void close()
    {
        if (frames) {
            std::fclose(frames);
        }
        if (truth) {
            std::fclose(truth);
        }
        frames = truth = nullptr;
    }
};

bool log_write(lcm_eventlog_t *log, const std::string &channel, int64_t utime, void *data,
               int32_t len)
{
    lcm_eventlog_event_t ev = lcm_eventlog_event_t();
    ev.timestamp = utime;
    ev.channellen = static_cast<int32_t>(channel.size());
    ev.channel = const_cast<char *>(channel.c_str());
    ev.datalen = len;
    ev.data = data;
    return lcm_eventlog_write_event(log, &ev) == 0;
}

/* Messages heard from the daemon go into the log as they are. */
struct Listener {
    lcm_eventlog_t *log = nullptr;
    int64_t n = 0, n_fail = 0;
};

void on_message(const lcm_recv_buf_t *rbuf, const char *channel, void *user)
{
    Listener *l = static_cast<Listener *>(user);
    if (!log_write(l->log, channel, rbuf->recv_utime, rbuf->data, static_cast<int32_t>(rbuf->data_size))) {
        ++l->n_fail;
    } else {
        ++l->n;
    }
}

int record(int argc, char **argv)
{
    std::string config, dir, logpath, listen, image_channel = "RIGPOSE_IMAGE", pose_ch, status_ch;
    long frames = 0, linger_ms = 500;
    bool fast = false;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        const bool v = i + 1 < argc;
        if (a == "--config" && v) {
            config = argv[++i];
        } else if (a == "--dir" && v) {
            dir = argv[++i];
        } else if (a == "--log" && v) {
            logpath = argv[++i];
        } else if (a == "--frames" && v) {
            frames = std::atol(argv[++i]);
        } else if (a == "--fast") {
            fast = true;
        } else if (a == "--listen" && v) {
            listen = argv[++i];
        } else if (a == "--image-channel" && v) {
            image_channel = argv[++i];
        } else if (a == "--pose-channel" && v) {
            pose_ch = argv[++i];
        } else if (a == "--status-channel" && v) {
            status_ch = argv[++i];
        } else if (a == "--linger-ms" && v) {
            linger_ms = std::atol(argv[++i]);
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (config.empty() || (dir.empty() && logpath.empty()) || frames < 0 ||
        (!listen.empty() && logpath.empty())) {
        std::fprintf(stderr, "rigpose-log: record needs --config and --dir and/or --log (--listen "
                             "needs --log)\n");
        usage(stderr);
        return 2;
    }
    static rp_config_t cfg;
    char err[RP_CFG_ERR_MAX];
    if (rp_config_load(config.c_str(), &cfg, err, sizeof err) != RP_CFG_OK) {
        std::fprintf(stderr, "rigpose-log: %s\n", err);
        return 2;
    }
    if (cfg.hal.kind == RP_HAL_SRC_SIM) {
        std::fprintf(stderr, "rigpose-log: %s: the sim source delivers features, not images: "
                             "record a v4l2 or replay source\n", config.c_str());
        return 2;
    }
    if (fast) {
        cfg.hal.realtime = 0;
    }
    const int n = cfg.hal.n_cams;
    rp_hal_source_t *src = nullptr;
    if (rp_hal_open(&src, &cfg.hal) != RP_HAL_OK || rp_hal_start(src) != RP_HAL_OK) {
        std::fprintf(stderr, "rigpose-log: source: %s\n", rp_hal_errmsg(src));
        if (src) {
            rp_hal_close(src);
        }
        return 3;
    }
    Folder folder;
    std::string why;
    if (!dir.empty() && (!folder.open(dir, n, true, &why) ||
                         !write_rig_yaml(config, dir + "/rig.yaml", n))) {
        std::fprintf(stderr, "rigpose-log: %s\n", why.empty() ? ("cannot write " + dir + "/rig.yaml").c_str() : why.c_str());
        rp_hal_close(src);
        return 3;
    }
    lcm_eventlog_t *log = nullptr;
    if (!logpath.empty() && !(log = lcm_eventlog_create(logpath.c_str(), "w"))) {
        std::fprintf(stderr, "rigpose-log: cannot write %s\n", logpath.c_str());
        rp_hal_close(src);
        return 3;
    }
    Listener listener;
    listener.log = log;
    lcm_t *lcm = nullptr;
    if (!listen.empty()) {
        lcm = lcm_create(listen.c_str());
        if (!lcm) {
            std::fprintf(stderr, "rigpose-log: cannot open LCM %s\n", listen.c_str());
            rp_hal_close(src);
            return 3;
        }
        lcm_subscribe(lcm, pose_ch.empty() ? cfg.pose_channel : pose_ch.c_str(), on_message, &listener);
        lcm_subscribe(lcm, status_ch.empty() ? cfg.status_channel : status_ch.c_str(), on_message,
                      &listener);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);

    int64_t sets = 0, lost = 0, missing = 0, write_fail = 0, consecutive_fail = 0;
    std::vector<uint32_t> drops(static_cast<size_t>(n), 0);
    const int64_t t0 = rp_hal_now_us();
    int64_t next_report = t0 + 1000000;
    static rp_hal_set_t set;
    std::vector<uint8_t> buf;
    int64_t t_end = 0; /* when recording ended (the rate leaves out the lingering) */
    auto progress = [&](const char *tag) {
        const double dt = static_cast<double>((t_end ? t_end : rp_hal_now_us()) - t0) * 1e-6;
        std::fprintf(stderr, "rigpose-log: %s %" PRId64 " sets, %.1f sets/s, drops", tag, sets,
                     dt > 0 ? static_cast<double>(sets) / dt : 0.0);
        for (int k = 0; k < n; ++k) {
            std::fprintf(stderr, " %s:%u", cfg.cam_name[k], drops[static_cast<size_t>(k)]);
        }
        std::fprintf(stderr, ", missing frames %" PRId64 ", lost sets %" PRId64, missing, lost);
        if (lcm) {
            std::fprintf(stderr, ", daemon messages %" PRId64, listener.n);
        }
        std::fprintf(stderr, "\n");
    };
    while (!g_stop && (frames == 0 || sets < frames)) {
        const rp_hal_status_t st = rp_hal_grab(src, &set);
        if (lcm) {
            while (lcm_handle_timeout(lcm, 0) > 0) {
            }
        }
        if (st == RP_HAL_E_END) {
            break;
        }
        if (st != RP_HAL_OK) {
            ++lost;
            std::fprintf(stderr, "rigpose-log: set lost (%s): %s\n", rp_hal_status_str(st),
                         rp_hal_errmsg(src));
            if (++consecutive_fail >= 20) {
                std::fprintf(stderr, "rigpose-log: 20 failures in a row: giving up\n");
                break;
            }
            continue;
        }
        consecutive_fail = 0;
        std::vector<const rp_image_t *> imgs(static_cast<size_t>(n), nullptr);
        for (int k = 0; k < n && k < set.n_cams; ++k) {
            const rp_hal_frame_t &f = set.cam[k];
            drops[static_cast<size_t>(k)] = f.drops;
            if (f.img.data && !(f.flags & RP_HAL_CAM_MISSING)) {
                imgs[static_cast<size_t>(k)] = &f.img;
            } else {
                ++missing;
                std::fprintf(stderr, "rigpose-log: set %u: %s missing\n", set.seq, cfg.cam_name[k]);
            }
        }
        double truth[6];
        for (int i = 0; i < 6; ++i) {
            truth[i] = static_cast<double>(set.truth[i]);
        }
        bool ok = true;
        if (!dir.empty() && !folder.add(set.utime, set.seq, imgs, set.has_truth ? truth : nullptr, &why)) {
            std::fprintf(stderr, "rigpose-log: set %u not written: %s\n", set.seq, why.c_str());
            ok = false;
        }
        for (int k = 0; log && k < n; ++k) {
            const rp_image_t *im = imgs[static_cast<size_t>(k)];
            if (!im) {
                continue;
            }
            rigpose_image_t m = rigpose_image_t();
            m.utime = set.cam[k].utime;
            m.seq = static_cast<int32_t>(set.seq);
            m.cam = static_cast<int8_t>(k);
            m.width = static_cast<int16_t>(im->w);
            m.height = static_cast<int16_t>(im->h);
            m.size = static_cast<int32_t>(im->w) * im->h;
            std::vector<uint8_t> packed(static_cast<size_t>(m.size));
            for (int y = 0; y < im->h; ++y) {
                std::memcpy(&packed[static_cast<size_t>(y) * im->w],
                            im->data + static_cast<size_t>(y) * im->stride, im->w);
            }
            m.data = packed.data();
            buf.resize(static_cast<size_t>(rigpose_image_t_encoded_size(&m)));
            rigpose_image_t_encode(buf.data(), 0, static_cast<int>(buf.size()), &m);
            if (!log_write(log, image_channel, set.utime, buf.data(), static_cast<int32_t>(buf.size()))) {
                std::fprintf(stderr, "rigpose-log: set %u: %s not written to the log\n", set.seq,
                             cfg.cam_name[k]);
                ok = false;
            }
        }
        if (ok) {
            ++sets;
        } else {
            ++write_fail;
            ++lost;
        }
        if (rp_hal_now_us() >= next_report) {
            progress("recording:");
            next_report += 1000000;
        }
    }
    t_end = rp_hal_now_us();
    if (lcm) { /* the daemon's last messages: until it is quiet for --linger-ms */
        while (linger_ms > 0 && lcm_handle_timeout(lcm, static_cast<int>(linger_ms)) > 0) {
        }
        lcm_destroy(lcm);
    }
    rp_hal_stop(src);
    rp_hal_close(src);
    folder.close();
    if (log) {
        lcm_eventlog_destroy(log);
    }
    progress(g_stop ? "stopped:" : "done:");
    if (listener.n_fail) {
        std::fprintf(stderr, "rigpose-log: %" PRId64 " daemon messages not written\n", listener.n_fail);
    }
    return lost || listener.n_fail ? 1 : 0;
}

int replay(int argc, char **argv)
{
    std::string in, dir, config, image_channel = "RIGPOSE_IMAGE";
    bool tolerant = false;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        const bool v = i + 1 < argc;
        if (a == "--dir" && v) {
            dir = argv[++i];
        } else if (a == "--config" && v) {
            config = argv[++i];
        } else if (a == "--image-channel" && v) {
            image_channel = argv[++i];
        } else if (a == "--tolerant") {
            tolerant = true;
        } else if (!a.empty() && a[0] != '-' && in.empty()) {
            in = a;
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (in.empty() || dir.empty()) {
        usage(stderr);
        return 2;
    }
    rp_lcmlog_t log;
    if (rp_lcmlog_open(&log, in.c_str(), tolerant) != 0) {
        std::fprintf(stderr, "rigpose-log: %s\n", log.err);
        rp_lcmlog_close(&log);
        return 3;
    }
    log.warn = stderr;
    log.prog = "rigpose-log";
    /* sets by seq: each camera's image (packed rows) */
    struct Img {
        int w = 0, h = 0;
        std::vector<uint8_t> px;
    };
    std::map<int32_t, std::pair<int64_t, std::map<int, Img>>> sets;
    int n_cams = 0;
    int64_t bad = 0;
    rp_lcmlog_event_t ev;
    int r;
    while ((r = rp_lcmlog_next(&log, &ev)) > 0) {
        if (image_channel != ev.channel) {
            continue;
        }
        rigpose_image_t m;
        if (rp_image_t_decode_checked(ev.data, static_cast<int>(ev.datalen), &m) < 0) {
            ++bad;
            continue;
        }
        if (m.width <= 0 || m.height <= 0 || m.size != static_cast<int32_t>(m.width) * m.height ||
            m.cam < 0 || m.cam >= RP_MAX_CAMS) {
            ++bad;
        } else {
            auto &s = sets[m.seq];
            if (s.second.empty()) {
                s.first = ev.timestamp;
            }
            Img &im = s.second[m.cam];
            im.w = m.width;
            im.h = m.height;
            im.px.assign(m.data, m.data + m.size);
            n_cams = std::max(n_cams, m.cam + 1);
        }
        rigpose_image_t_decode_cleanup(&m);
    }
    if (r < 0) { /* truncated or corrupt: nothing written (--tolerant reads on) */
        std::fprintf(stderr, "rigpose-log: %s\n", log.err);
        rp_lcmlog_close(&log);
        return 1;
    }
    rp_lcmlog_close(&log);
    if (bad) {
        std::fprintf(stderr, "rigpose-log: %s: %" PRId64 " messages on %s are not valid images\n",
                     in.c_str(), bad, image_channel.c_str());
    }
    if (sets.empty()) {
        std::fprintf(stderr, "rigpose-log: %s: no rigpose.image_t on %s\n", in.c_str(),
                     image_channel.c_str());
        return 1;
    }
    Folder folder;
    std::string why;
    if (!folder.open(dir, n_cams, false, &why)) {
        std::fprintf(stderr, "rigpose-log: %s\n", why.c_str());
        return 3;
    }
    int64_t written = 0, incomplete = 0;
    for (auto &s : sets) {
        std::vector<rp_image_t> imgs(static_cast<size_t>(n_cams));
        std::vector<const rp_image_t *> ptr(static_cast<size_t>(n_cams), nullptr);
        for (auto &c : s.second.second) {
            rp_image_t &im = imgs[static_cast<size_t>(c.first)];
            im.data = c.second.px.data();
            im.w = static_cast<uint16_t>(c.second.w);
            im.h = static_cast<uint16_t>(c.second.h);
            im.stride = static_cast<uint32_t>(c.second.w);
            im.size = static_cast<uint32_t>(c.second.px.size());
            ptr[static_cast<size_t>(c.first)] = &im;
        }
        if (static_cast<int>(s.second.second.size()) < n_cams) {
            ++incomplete;
            std::fprintf(stderr, "rigpose-log: set %d: %zu of %d cameras (missing columns left empty)\n",
                         s.first, s.second.second.size(), n_cams);
        }
        if (!folder.add(s.second.first, static_cast<uint32_t>(s.first), ptr, nullptr, &why)) {
            std::fprintf(stderr, "rigpose-log: set %d: %s\n", s.first, why.c_str());
            folder.close();
            return 1;
        }
        ++written;
    }
    folder.close();
    if (!config.empty() && !write_rig_yaml(config, dir + "/rig.yaml", n_cams)) {
        std::fprintf(stderr, "rigpose-log: cannot write %s/rig.yaml from %s\n", dir.c_str(),
                     config.c_str());
        return 1;
    }
    std::fprintf(stderr, "rigpose-log: %" PRId64 " sets of %d cameras from %s into %s (%" PRId64
                         " incomplete)\n", written, n_cams, in.c_str(), dir.c_str(), incomplete);
    return incomplete ? 1 : 0;
}

/* `mcap`: hands the log to rigpose-view (Python, foxglove-sdk), found beside this program. */
int to_mcap(int argc, char **argv)
{
    if (argc < 4) {
        usage(stderr);
        return 2;
    }
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) {
        std::fprintf(stderr, "rigpose-log: cannot find its own path: %s\n", std::strerror(errno));
        return 3;
    }
    self[n] = '\0';
    std::string view(self);
    view = view.substr(0, view.find_last_of('/') + 1) + "rigpose-view";
    std::vector<char *> args;
    args.push_back(const_cast<char *>(view.c_str()));
    const char *fixed[] = {"--lcm-log", argv[2], "--mcap", argv[3]};
    for (const char *a : fixed) args.push_back(const_cast<char *>(a));
    for (int i = 4; i < argc; i++) args.push_back(argv[i]);
    args.push_back(nullptr);
    execv(view.c_str(), args.data());
    std::fprintf(stderr, "rigpose-log: cannot run %s: %s\n", view.c_str(), std::strerror(errno));
    return 3;
}

} // namespace

int main(int argc, char **argv)
{
    if (argc >= 2 && std::strcmp(argv[1], "mcap") == 0) {
        return to_mcap(argc, argv);
    }
    if (argc >= 2 && std::strcmp(argv[1], "record") == 0) {
        return record(argc, argv);
    }
    if (argc >= 2 && std::strcmp(argv[1], "replay") == 0) {
        return replay(argc, argv);
    }
    const bool help = argc >= 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"));
    usage(help ? stdout : stderr);
    return help ? 0 : 2;
}
