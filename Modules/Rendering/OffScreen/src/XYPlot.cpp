#include "cementsph/rendering/XYPlot.h"

#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContext2D.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPlot.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkTransform2D.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace cementsph::rendering {
namespace {

// Draws labels[i] beside the data point (x[i], y[i]), offset by a few pixels.
// toPlot maps data coordinates to the plot's (vtkPlot::TransformDataToScreen, protected there).
void paintPointLabels(vtkContext2D* painter, vtkPlot* plot, const std::vector<std::string>& labels,
                      const std::vector<double>& x, const std::vector<double>& y,
                      const std::function<void(double, double, double&, double&)>& toPlot) {
  vtkMatrix3x3* m = painter->GetTransform()->GetMatrix();
  const double sx = m->GetElement(0, 0) != 0 ? m->GetElement(0, 0) : 1.0; // pixels per plot unit
  const double sy = m->GetElement(1, 1) != 0 ? m->GetElement(1, 1) : 1.0;
  vtkTextProperty* text = painter->GetTextProp();
  text->SetFontSize(13);
  text->SetBold(false);
  text->SetItalic(false);
  text->SetJustificationToLeft();
  text->SetVerticalJustificationToBottom();
  unsigned char rgba[4];
  plot->GetColor(rgba);
  text->SetColor(rgba[0] / 255.0, rgba[1] / 255.0, rgba[2] / 255.0);
  for (std::size_t i = 0; i < labels.size() && i < x.size() && i < y.size(); ++i) {
    if (labels[i].empty()) continue;
    double px = 0, py = 0;
    toPlot(x[i], y[i], px, py);
    painter->DrawString(static_cast<float>(px + 6.0 / sx), static_cast<float>(py + 4.0 / sy), labels[i]);
  }
}

// Line and point plots that also write a text label beside each point (PlotSeries::pointLabels). VTK's
// charts have tooltips but no static point labels; the labels are drawn in the plot's own Paint, where the
// painter maps plot coordinates to pixels, and TransformDataToScreen applies the log axes and the chart's
// shift and scale.
template <class Base> class vtkLabelledPlot : public Base {
public:
  static vtkLabelledPlot* New() {
    auto* plot = new vtkLabelledPlot;
    plot->InitializeObjectBase();
    return plot;
  }
  vtkTypeMacro(vtkLabelledPlot, Base)
  std::vector<std::string> Labels;
  std::vector<double> X, Y; // data coordinates of the labelled points

  bool Paint(vtkContext2D* painter) override {
    if (!Base::Paint(painter)) return false;
    paintPointLabels(painter, this, Labels, X, Y,
                     [this](double x, double y, double& px, double& py) { this->TransformDataToScreen(x, y, px, py); });
    return true;
  }

protected:
  vtkLabelledPlot() = default;
  ~vtkLabelledPlot() override = default;
};

// Makes the labelled twin of the plot type AddPlot would make for this style.
template <class Base> vtkSmartPointer<vtkPlotPoints> labelledPlot(const PlotSeries& s) {
  auto plot = vtkSmartPointer<vtkLabelledPlot<Base>>::Take(vtkLabelledPlot<Base>::New());
  plot->Labels = s.pointLabels;
  plot->X = s.x;
  plot->Y = s.y;
  return plot;
}

std::string seriesName(const PlotSeries& s, std::size_t index) {
  return s.name.empty() ? "series #" + std::to_string(index) : "series '" + s.name + "'";
}

std::string show(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

[[noreturn]] void reject(const std::string& why) { throw std::invalid_argument("writePlotPng: " + why); }

void checkValues(const std::vector<double>& values, const char* axis, bool logAxis, const std::string& who) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (!std::isfinite(v)) reject(who + ": " + axis + "[" + std::to_string(i) + "] is " + show(v));
    if (logAxis && v <= 0.0) {
      reject(who + ": " + axis + "[" + std::to_string(i) + "] = " + show(v) + " is not positive, but the " +
             axis + " axis is logarithmic");
    }
  }
}

void checkLimit(const std::optional<double>& limit, const char* name, bool logAxis) {
  if (!limit) return;
  if (!std::isfinite(*limit)) reject(std::string(name) + " is " + show(*limit));
  if (logAxis && *limit <= 0.0) {
    reject(std::string(name) + " = " + show(*limit) + " is not positive, but its axis is logarithmic");
  }
}

// The axis range to fix, or nothing to let VTK choose a "nice" one. A limit left empty next to a given one
// comes from the data.
std::optional<std::pair<double, double>> axisRange(const PlotSpec& spec, bool xAxis) {
  const auto& lo = xAxis ? spec.xMin : spec.yMin;
  const auto& hi = xAxis ? spec.xMax : spec.yMax;
  if (!lo && !hi) return std::nullopt;
  double dataMin = HUGE_VAL, dataMax = -HUGE_VAL;
  for (const auto& s : spec.series) {
    const auto& v = xAxis ? s.x : s.y;
    const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
    dataMin = std::min(dataMin, *mn);
    dataMax = std::max(dataMax, *mx);
  }
  const double a = lo.value_or(dataMin), b = hi.value_or(dataMax);
  if (!(a < b)) {
    reject(std::string(xAxis ? "x" : "y") + " axis range [" + show(a) + ", " + show(b) +
           "] is empty (limits given: " + (lo ? "min " : "") + (hi ? "max" : "") + ")");
  }
  return std::make_pair(a, b);
}

void setUpAxis(vtkAxis* axis, const std::string& title, bool logScale,
               const std::optional<std::pair<double, double>>& range) {
  axis->SetTitle(title);
  axis->SetLogScale(logScale);
  if (range) {
    axis->SetBehavior(vtkAxis::FIXED);
    // Unscaled: the limits are data values even on a log axis (SetRange would take exponents there).
    axis->SetUnscaledRange(range->first, range->second);
  }
}

} // namespace

void validatePlotSpec(const PlotSpec& spec) {
  if (spec.widthPx < 32 || spec.heightPx < 32 || spec.widthPx > 8192 || spec.heightPx > 8192) {
    reject("image size " + std::to_string(spec.widthPx) + " x " + std::to_string(spec.heightPx) +
           " px is outside 32..8192");
  }
  if (spec.series.empty()) reject("the plot has no series");
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    const std::string who = seriesName(s, i);
    if (s.x.size() != s.y.size()) {
      reject(who + ": x has " + std::to_string(s.x.size()) + " values but y has " + std::to_string(s.y.size()));
    }
    if (s.x.empty()) reject(who + " has no points");
    if (!s.pointLabels.empty() && s.pointLabels.size() != s.x.size()) {
      reject(who + ": " + std::to_string(s.pointLabels.size()) + " point labels for " + std::to_string(s.x.size()) +
             " points");
    }
    checkValues(s.x, "x", spec.logX, who);
    checkValues(s.y, "y", spec.logY, who);
    if (!std::isfinite(s.width) || s.width <= 0.0) reject(who + ": width " + show(s.width) + " is not positive");
  }
  checkLimit(spec.xMin, "xMin", spec.logX);
  checkLimit(spec.xMax, "xMax", spec.logX);
  checkLimit(spec.yMin, "yMin", spec.logY);
  checkLimit(spec.yMax, "yMax", spec.logY);
  axisRange(spec, true);
  axisRange(spec, false);
}

void writePlotPng(const PlotSpec& spec, const std::filesystem::path& png) {
  validatePlotSpec(spec);

  auto window = makeOffScreenRenderWindow(spec.widthPx, spec.heightPx);
  auto view = vtkSmartPointer<vtkContextView>::New();
  view->SetRenderWindow(window);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);

  auto chart = vtkSmartPointer<vtkChartXY>::New();
  view->GetScene()->AddItem(chart);
  chart->SetTitle(spec.title);
  chart->GetTitleProperties()->SetFontSize(16);
  chart->SetShowLegend(spec.series.size() > 1);
  if (spec.series.size() > 1) {
    chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
    chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  }

  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    // One table per series: series need not share x values.
    auto table = vtkSmartPointer<vtkTable>::New();
    auto xs = vtkSmartPointer<vtkDoubleArray>::New();
    auto ys = vtkSmartPointer<vtkDoubleArray>::New();
    xs->SetName("x");
    ys->SetName(s.name.empty() ? "y" : s.name.c_str());
    table->AddColumn(xs);
    table->AddColumn(ys);
    table->SetNumberOfRows(static_cast<vtkIdType>(s.x.size()));
    for (std::size_t r = 0; r < s.x.size(); ++r) {
      table->SetValue(static_cast<vtkIdType>(r), 0, vtkVariant(s.x[r]));
      table->SetValue(static_cast<vtkIdType>(r), 1, vtkVariant(s.y[r]));
    }

    vtkPlot* plot = nullptr;
    if (s.pointLabels.empty()) {
      plot = chart->AddPlot(s.style == PlotSeries::Style::Points ? vtkChart::POINTS : vtkChart::LINE);
    } else {
      // The same plot types as AddPlot makes, with the labels painted on top (the chart keeps a reference).
      vtkSmartPointer<vtkPlotPoints> labelled = s.style == PlotSeries::Style::Points ? labelledPlot<vtkPlotPoints>(s)
                                                                                     : labelledPlot<vtkPlotLine>(s);
      chart->AddPlot(labelled);
      plot = labelled;
    }
    plot->SetInputData(table, 0, 1);
    plot->SetColor(s.rgb[0], s.rgb[1], s.rgb[2], 255);
    plot->SetWidth(static_cast<float>(s.width));
    plot->SetLabel(s.name);
    if (auto* points = vtkPlotPoints::SafeDownCast(plot)) { // lines are vtkPlotPoints too
      points->SetMarkerStyle(s.style == PlotSeries::Style::Line ? vtkPlotPoints::NONE : vtkPlotPoints::CIRCLE);
      points->SetMarkerSize(static_cast<float>(std::max(4.0, 3.0 * s.width)));
    }
  }

  setUpAxis(chart->GetAxis(vtkAxis::BOTTOM), spec.xLabel, spec.logX, axisRange(spec, true));
  setUpAxis(chart->GetAxis(vtkAxis::LEFT), spec.yLabel, spec.logY, axisRange(spec, false));

  writeWindowPng(window, png);
}

} // namespace cementsph::rendering
