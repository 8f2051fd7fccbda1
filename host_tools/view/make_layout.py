#!/usr/bin/env python3
"""make_layout.py [OUT.json] - writes the Foxglove layout for rigpose-view's topics
(host_tools/view/rigpose.layout.json; `make view-layout` regenerates it) with foxglove-sdk's
layout classes: a 3D panel following cam1 (the rig's frusta, the pose, the trajectory), the
image of cam1 with its annotations, plots of features used per camera, latency and filter
health, and the latest status message. Import it in Foxglove: Layouts -> Import from file.
"""
import sys

import foxglove.layouts as fl


def plot(title, series):
    return fl.PlotPanel(title=title, config=fl.PlotConfig(
        paths=[fl.PlotSeries(value=v, label=l) for v, l in series], show_legend=True,
        legend_display="floating", x_axis_val="timestamp"))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "host_tools/view/rigpose.layout.json"
    three_d = fl.ThreeDeePanel(title="rig, pose and trajectory", config=fl.ThreeDeeConfig(
        follow_tf="cam1", fixed_frame="world",
        topics={"/rigpose/rig": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
                "/rigpose/pose": fl.BaseRendererPoseTopicSettings(visible=True, type="axis",
                                                                  axis_scale=0.05),
                "/rigpose/trajectory": fl.BaseRendererPosesTopicSettings(
                    visible=True, type="line", line_width=0.003)}))
    image = fl.ImagePanel(title="cam1", config=fl.ImageConfig(image_mode=fl.ImageModeConfig(
        image_topic="/rigpose/cam1/image",
        annotations={"/rigpose/cam1/annotations": fl.ImageAnnotationSettings(visible=True)})))
    features = plot("features used per camera", [
        ("/rigpose/pose_info.features_used[%d]" % k, "cam%d" % (k + 1)) for k in range(4)])
    latency = plot("latency and processing, ms", [
        ("/rigpose/pose_info.latency_ms", "frame -> publish"),
        ("/rigpose/status.process_ms", "estimator"),
        ("/rigpose/status.latency_ms_max", "worst in period")])
    health = plot("filter health", [
        ("/rigpose/status.pos_sigma_m", "position sigma, m"),
        ("/rigpose/status.n_lost", "lost sets"), ("/rigpose/status.n_reinit", "re-inits"),
        ("/rigpose/status.n_cov_reset", "covariance resets"),
        ("/rigpose/pose_info.error_position_m", "error vs truth, m")])
    status = fl.RawMessagesPanel(title="status", config=fl.RawMessagesConfig(
        topic_path="/rigpose/status"))
    layout = fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=3, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(proportion=2, content=three_d), fl.SplitItem(proportion=1,
                                                                       content=image)])),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(proportion=1, content=features),
            fl.SplitItem(proportion=1, content=latency),
            fl.SplitItem(proportion=1, content=health),
            fl.SplitItem(proportion=1, content=status)]))]))
    import json
    with open(out, "w") as f:
        json.dump(json.loads(layout.to_json()), f, indent=1, sort_keys=True)
        f.write("\n")
    print("make_layout: %s" % out)


if __name__ == "__main__":
    main()
