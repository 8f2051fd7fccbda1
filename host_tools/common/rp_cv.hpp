/*
 * rp_cv.hpp - host-side glue between OpenCV and the core (host tools and oracle tests only;
 * never included by core/ or the daemon).
 */
#ifndef RP_CV_HPP
#define RP_CV_HPP

#include <opencv2/core.hpp>

#include "rigpose/rp_track.h"

/* A cv::Mat (CV_8U, one channel) as the core's rp_image_t, borrowed: the Mat must outlive it. */
inline rp_image_t rp_cv_view(const cv::Mat &m)
{
    rp_image_t im;
    im.data = m.data;
    im.w = (uint16_t)m.cols;
    im.h = (uint16_t)m.rows;
    im.stride = (uint32_t)m.step[0];
    im.size = (uint32_t)(m.step[0] * (size_t)m.rows);
    return im;
}

#endif /* RP_CV_HPP */
