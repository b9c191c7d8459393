// The run summary in constant memory (cape/scenes/Metrics.h): PercentileEstimator is exact up to its
// kExactValues values and within its documented error of the exact nearest-rank percentile after, and
// MetricsRecorder gives the same figures as the exact computation over every frame.
#include "cape/scenes/Metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace cape {
namespace {

/// The documented bound on |estimate - exact|.
double allowedError(double exact) {
  const double magnitude = std::abs(exact);
  if (magnitude < PercentileEstimator::kSmallest) return PercentileEstimator::kSmallest;
  return PercentileEstimator::kRelativeError * magnitude * (1.0 + 1e-9);  // and rounding
}

const double kPercentiles[] = {0.0, 0.1, 1.0, 5.0, 25.0, 50.0, 75.0, 90.0, 95.0, 99.0, 99.9, 100.0};

TEST(PercentileEstimator, IsExactUpToItsKeptValues) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PercentileEstimator e;
  std::vector<double> all;
  for (std::size_t i = 0; i < PercentileEstimator::kExactValues; ++i) {
    all.push_back(u(random));
    e.add(all.back());
  }
  ASSERT_TRUE(e.exact());
  for (double p : kPercentiles) EXPECT_EQ(e.percentile(p), percentile(all, p)) << p;
  e.add(0.5);
  EXPECT_FALSE(e.exact());
  EXPECT_EQ(PercentileEstimator().percentile(50.0), 0.0) << "no values";
}

// A generated sequence like a long run's per-frame max strain and frame times: log-normal magnitudes over
// six decades, a share of them negative (compressed), exact zeros, values below kSmallest, a slow drift and
// rare spikes; every percentile within the documented error of the exact one.
TEST(PercentileEstimator, StaysWithinItsDocumentedErrorOfTheExactPercentile) {
  std::mt19937_64 random(2024);
  std::lognormal_distribution<double> strain(std::log(0.014), 0.4);
  std::lognormal_distribution<double> wide(0.0, 3.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PercentileEstimator e;
  std::vector<double> all;
  const int n = 300000;
  for (int i = 0; i < n; ++i) {
    const double draw = u(random);
    double v = strain(random) * (1.0 + 2.5 * i / n);  // the drift: 1.4 % to about 5 %
    if (draw < 0.05) v = -v;
    if (draw > 0.05 && draw < 0.06) v = 0.0;
    if (draw > 0.06 && draw < 0.07) v = 1e-11 * u(random);
    if (draw > 0.07 && draw < 0.20) v = wide(random);
    if (draw > 0.9999) v = 4.12;  // a spike
    all.push_back(v);
    e.add(v);
  }
  EXPECT_EQ(e.count(), n);
  for (double p : kPercentiles) {
    const double exact = percentile(all, p);
    EXPECT_NEAR(e.percentile(p), exact, allowedError(exact)) << "p" << p;
  }
  EXPECT_EQ(e.percentile(0.0), *std::min_element(all.begin(), all.end())) << "the extremes stay exact";
  EXPECT_EQ(e.percentile(100.0), *std::max_element(all.begin(), all.end()));
}

TEST(PercentileEstimator, ClampsFarValuesBetweenTheExtremesAndSkipsNaN) {
  PercentileEstimator e;
  for (std::size_t i = 0; i <= PercentileEstimator::kExactValues; ++i) e.add(i % 2 ? 1e15 : -1e15);
  e.add(std::nan(""));
  EXPECT_EQ(e.count(), static_cast<std::int64_t>(PercentileEstimator::kExactValues) + 1);
  EXPECT_GE(e.percentile(75.0), -1e15);
  EXPECT_LE(e.percentile(75.0), 1e15);
  EXPECT_GT(e.percentile(75.0), 0.0);
  EXPECT_LT(e.percentile(25.0), 0.0);
}

// A one-hour run's worth of frames through the recorder: the figures a summary gives against the exact
// computation over all frames (kept here, as the recorder no longer does).
TEST(MetricsRecorder, AnHourOfFramesSummarisesAsTheExactComputation) {
  std::mt19937 random(11);
  std::lognormal_distribution<float> strain(std::log(0.014f), 0.5f);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  MetricsRecorder rec;
  std::vector<FrameMetrics> frames;
  const int n = 60 * 3600;
  for (int i = 0; i < n; ++i) {
    FrameMetrics m;
    m.maxStrain = strain(random);
    m.meanStrain = 0.1f * m.maxStrain;
    m.maxPenetration = u(random) < 0.01f ? 0.002f : 0.0f;
    m.selfIntersections = u(random) < 0.001f ? 2 : 0;
    m.pinError = 1e-6f * u(random);
    m.meanSpeed = u(random);
    frames.push_back(m);
    rec.add(m);
  }
  const RunSummary s = rec.summary();
  std::vector<double> maxStrains;
  double meanSum = 0.0, lastSecond = 0.0;
  std::int64_t over1mm = 0, withSelf = 0;
  float maxStrain = frames.front().maxStrain, pinError = 0.0f;
  for (const FrameMetrics& f : frames) {
    maxStrains.push_back(f.maxStrain);
    meanSum += f.meanStrain;
    maxStrain = std::max(maxStrain, f.maxStrain);
    pinError = std::max(pinError, f.pinError);
    over1mm += f.maxPenetration > 1e-3f ? 1 : 0;
    withSelf += f.selfIntersections > 0 ? 1 : 0;
  }
  for (std::size_t i = frames.size() - 60; i < frames.size(); ++i) lastSecond += frames[i].meanSpeed;
  EXPECT_EQ(s.frames, n);
  EXPECT_EQ(s.maxStrain, maxStrain);
  EXPECT_EQ(s.meanStrain, meanSum / n);
  EXPECT_EQ(s.pinErrorMax, pinError);
  EXPECT_EQ(s.framesPenetrationOver1mm, over1mm);
  EXPECT_EQ(s.framesWithSelfIntersections, withSelf);
  EXPECT_EQ(s.selfIntersectionsMax, 2);
  EXPECT_EQ(s.restJitter, static_cast<float>(lastSecond / 60.0)) << "the same sum in the same order";
  const double median = percentile(maxStrains, 50.0), p95 = percentile(maxStrains, 95.0);
  // Within the estimator's error, and the float the summary keeps it in.
  EXPECT_NEAR(s.medianFrameMaxStrain, median, allowedError(median) + 1e-7 * median);
  EXPECT_NEAR(s.p95FrameMaxStrain, p95, allowedError(p95) + 1e-7 * p95);
  EXPECT_NE(s.p95FrameMaxStrain, s.medianFrameMaxStrain);
}

TEST(MetricsRecorder, RestJitterIsTheLastSecondEvenInShortRuns) {
  MetricsRecorder rec(0.25);  // four frames per second
  for (float speed : {1.0f, 2.0f}) {
    FrameMetrics m;
    m.meanSpeed = speed;
    rec.add(m);
  }
  EXPECT_FLOAT_EQ(rec.summary().restJitter, 1.5f) << "fewer frames than a second: all of them";
  for (float speed : {3.0f, 4.0f, 5.0f, 6.0f, 7.0f}) {
    FrameMetrics m;
    m.meanSpeed = speed;
    rec.add(m);
  }
  EXPECT_FLOAT_EQ(rec.summary().restJitter, 5.5f) << "the last four";
}

}  // namespace
}  // namespace cape
