#pragma once
// The log of farm-coordinator and farm-worker on stderr: lines for a person ("text"), or one
// JSON object per line for a log collector ("json": time, level, program, message; the message
// escaped, so a scene path with quotes or a newline stays one valid object).
#include <string>

namespace CLI {
class App;
}

namespace farm {

enum class LogFormat { kText, kJson };

// False for anything but "text" or "json".
bool parseLogFormat(const std::string& name, LogFormat* format);

// --log-format text|json (and FARM_LOG_FORMAT) on a program's command line.
void addLogFormatOption(CLI::App* app, std::string* name);

// Makes spdlog's default logger write `program`'s lines to stderr in `format`.
void setUpLogging(const std::string& program, LogFormat format);

// What ends a program after setUpLogging: an error line in the log (json), or "PROGRAM:
// MESSAGE" on stderr (text). Returns `code`, for `return fatal(...)`.
int logFatal(const std::string& program, LogFormat format, const std::string& message, int code);

}  // namespace farm
