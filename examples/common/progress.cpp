// examples/common/progress.cpp - a run's progress on stderr from a thread of its own
// (progress.h).
#include "examples/common/progress.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "examples/common/cli.h"

namespace mbr {

ProgressReporter::ProgressReporter(bool on, double interval)
    : on_(on), terminal_(on && isatty(2)), interval_(interval), next_line_(interval) {
    start_ = stage_start_ = now_seconds();
    if (on_) thread_ = std::thread([this] { run(); });
}

ProgressReporter::~ProgressReporter() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (drawn_) {
        std::fprintf(stderr, "\r%*s\r", 110, "");
        std::fflush(stderr);
    }
}

void ProgressReporter::stage(const std::string& text) {
    if (!on_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    stage_ = text;
    detail_.clear();
    fraction_ = seconds_left_ = -1;
    stage_start_ = now_seconds();
    if (terminal_) show_locked(line_locked(stage_start_));  // each new stage at once
}

void ProgressReporter::update(const std::string& text, double fraction) {
    if (!on_) return;
    double left = -1;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        const double elapsed = now_seconds() - stage_start_;
        if (fraction > 0 && fraction < 1) left = elapsed * (1 - fraction) / fraction;
    }
    update(text, fraction, left);
}

void ProgressReporter::update(const std::string& text, double fraction, double seconds_left) {
    if (!on_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    detail_ = text;
    fraction_ = fraction;
    seconds_left_ = seconds_left;
    estimated_at_ = now_seconds();
    // The end of a stage that the log has shown is said at once.
    if (!terminal_ && fraction >= 1 && now_seconds() - start_ >= interval_)
        show_locked(line_locked(now_seconds()));
    draw_now_locked();
}

void ProgressReporter::draw_now_locked() {
    // On a terminal an event redraws the line at once, at most ten times a second.
    if (!terminal_) return;
    const double now = now_seconds();
    if (now - last_draw_ < 0.1) return;
    show_locked(line_locked(now));
}

std::string format_duration(double seconds) {
    char text[32];
    if (seconds < 100)
        std::snprintf(text, sizeof text, "%.0f s", seconds);
    else if (seconds < 7200)
        std::snprintf(text, sizeof text, "%.0f min", seconds / 60);
    else
        std::snprintf(text, sizeof text, "%.1f h", seconds / 3600);
    return text;
}

std::string ProgressReporter::line_locked(double now) const {
    if (stage_.empty()) return "";
    std::string line;
    if (terminal_ && fraction_ >= 0) {
        const int width = 20;
        const int filled = int(std::clamp(fraction_, 0.0, 1.0) * width);
        line = "[" + std::string(size_t(filled), '#') + std::string(size_t(width - filled), '.') +
               "] ";
    }
    line += stage_;
    if (!detail_.empty()) line += ": " + detail_;
    char tail[96];
    // The estimate less the time since it was given; once that has run out the estimate was
    // wrong, and the line says only the time so far until the next event gives a new one.
    const double left = seconds_left_ - (now - estimated_at_);
    if (seconds_left_ >= 0 && left > 0)
        std::snprintf(tail, sizeof tail, ", %.1f s, about %s left", now - stage_start_,
                      format_duration(left).c_str());
    else
        std::snprintf(tail, sizeof tail, ", %.1f s", now - stage_start_);
    return line + tail;
}

void ProgressReporter::show_locked(const std::string& line) {
    if (line.empty()) return;
    if (terminal_) {
        std::string shown = line.substr(0, 105);
        std::fprintf(stderr, "\r%-105s", shown.c_str());
        drawn_ = true;
        last_draw_ = now_seconds();
    } else {
        std::fprintf(stderr, "%s\n", line.c_str());
        next_line_ = (now_seconds() - start_) + interval_;
    }
    std::fflush(stderr);
}

void ProgressReporter::run() {
    // A terminal is redrawn four times a second (its clock moves on between events); a log gets
    // a line every `interval` seconds.
    const double tick = terminal_ ? 0.25 : std::min(0.5, interval_ / 4);
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
        wake_.wait_for(lock, std::chrono::duration<double>(tick));
        if (stop_) break;
        const double now = now_seconds();
        const double t = now - start_;
        if (terminal_ || t >= next_line_) show_locked(line_locked(now));
    }
}

}  // namespace mbr
