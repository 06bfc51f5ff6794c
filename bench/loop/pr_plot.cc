#include "loop/pr_plot.h"

#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace rmap::bench {

cv::Mat drawPrCurves(const std::vector<PrCurve>& curves, const std::string& title, int width, int height) {
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 70, right = 20, top = 40, bottom = 55;
  const int w = width - left - right, h = height - top - bottom;
  auto at = [&](double recall, double precision) {
    return cv::Point(left + static_cast<int>(recall * w + 0.5), top + static_cast<int>((1.0 - precision) * h + 0.5));
  };
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (int i = 0; i <= 10; ++i) {
    const double v = i / 10.0;
    cv::line(img, at(v, 0.0), at(v, 1.0), cv::Scalar(225, 225, 225), 1);
    cv::line(img, at(0.0, v), at(1.0, v), cv::Scalar(225, 225, 225), 1);
    char label[8];
    std::snprintf(label, sizeof label, "%.1f", v);
    cv::putText(img, label, at(v, 0.0) + cv::Point(-10, 18), font, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
    cv::putText(img, label, at(0.0, v) + cv::Point(-30, 4), font, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
  cv::rectangle(img, at(0.0, 1.0), at(1.0, 0.0), cv::Scalar(0, 0, 0), 1);
  cv::putText(img, "recall", cv::Point(left + w / 2 - 20, height - 12), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "precision", cv::Point(4, top - 10), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, title, cv::Point(left + 60, top - 14), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

  const cv::Scalar colours[] = {{200, 60, 30}, {30, 140, 30}, {30, 30, 210}, {150, 30, 150}, {20, 140, 200}};
  for (size_t c = 0; c < curves.size(); ++c) {
    const cv::Scalar colour = colours[c % std::size(colours)];
    const PrCurve& curve = curves[c];
    cv::Point previous = at(0.0, curve.points.empty() ? 1.0 : curve.points.front().precision);
    for (const PrPoint& p : curve.points) {
      const cv::Point next = at(p.recall, p.precision);
      cv::line(img, previous, next, colour, 2, cv::LINE_AA);
      previous = next;
    }
    char label[96];
    std::snprintf(label, sizeof label, "k=%lld: R@100%%P %.1f%%, AUC %.3f", static_cast<long long>(curve.tolerance),
                  100.0 * curve.recall_at_100_precision, curve.auc);
    const cv::Point origin(left + 12, top + h - 16 - 20 * static_cast<int>(curves.size() - 1 - c));
    cv::line(img, origin + cv::Point(0, -4), origin + cv::Point(24, -4), colour, 2, cv::LINE_AA);
    cv::putText(img, label, origin + cv::Point(30, 0), font, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return img;
}

}  // namespace rmap::bench
