#include "ops/structured_log.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>

namespace farm {
namespace {

// %j: the message as the inside of a JSON string (RFC 8259: quote, backslash and control
// characters escaped; the rest, UTF-8 included, as is).
class JsonMessage final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&,
              spdlog::memory_buf_t& dest) override {
    for (char c : msg.payload) {
      switch (c) {
        case '"':
          dest.append(std::string_view("\\\""));
          break;
        case '\\':
          dest.append(std::string_view("\\\\"));
          break;
        case '\n':
          dest.append(std::string_view("\\n"));
          break;
        case '\r':
          dest.append(std::string_view("\\r"));
          break;
        case '\t':
          dest.append(std::string_view("\\t"));
          break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char escaped[8];
            std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned char>(c));
            dest.append(std::string_view(escaped));
          } else {
            dest.push_back(c);
          }
      }
    }
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<JsonMessage>();
  }
};

}  // namespace

bool parseLogFormat(const std::string& name, LogFormat* format) {
  if (name == "text") {
    *format = LogFormat::kText;
  } else if (name == "json") {
    *format = LogFormat::kJson;
  } else {
    return false;
  }
  return true;
}

void addLogFormatOption(CLI::App* app, std::string* name) {
  app->add_option("--log-format", *name,
                  "text (lines for a person) or json (one object per line: time, level, "
                  "program, message) on stderr")
      ->check(CLI::IsMember({"text", "json"}))
      ->default_str("text")
      ->envname("FARM_LOG_FORMAT");
}

int logFatal(const std::string& program, LogFormat format, const std::string& message, int code) {
  if (format == LogFormat::kJson) {
    spdlog::error("{}", message);
  } else {
    std::cerr << program << ": " << message << "\n";
  }
  return code;
}

void setUpLogging(const std::string& program, LogFormat format) {
  spdlog::set_default_logger(spdlog::stderr_logger_mt(program));
  if (format == LogFormat::kText) {
    spdlog::set_pattern("[%Y-%m-%d %H:%M:%S.%e] [" + program + "] %v");
    return;
  }
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<JsonMessage>('j').set_pattern(
      "{\"time\":\"%Y-%m-%dT%H:%M:%S.%e%z\",\"level\":\"%l\",\"program\":\"" + program +
      "\",\"message\":\"%j\"}");
  spdlog::set_formatter(std::move(formatter));
}

}  // namespace farm
