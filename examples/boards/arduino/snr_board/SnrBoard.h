// SnrBoard.h: SNR pages over Serial for an Arduino (Uno, Nano, Mega, ...).
//
// The board's end of SNR's serial link (docs/serial.md, "The board protocol"):
//   * begin() stops the actuators, then prints the ready line;
//   * poll() reads page lines such as {"key":"motor","data":[50,-50]} and
//     hands each to your handler as a key and up to SNR_MAX_VALUES numbers;
//   * poll() sends a heartbeat every SNR_HEARTBEAT_MS and calls your
//     failsafe handler when no page line (a command or a heartbeat) came for
//     SNR_FAILSAFE_MS: stop the motors there; while it hears nothing it
//     repeats the ready line every SNR_FAILSAFE_MS (for a computer that opens
//     the port without resetting the board, as on a GPIO UART);
//   * send() writes a page line back: {"key":"depth_m","data":2.41}.
//
// The parser is a small hand-written one: data must be a number or a list of
// numbers, and the key must come first (SNR's page lines always start with
// it). Anything else is counted in badLines and skipped.
#pragma once

#include <Arduino.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

// The protocol: these must match snr/extras/serial/board.py.
#define SNR_READY_LINE "{\"format\":\"snr-pages\",\"version\":1}"
#define SNR_HEARTBEAT_KEY "hb"
#define SNR_HEARTBEAT_MS 200
#define SNR_FAILSAFE_MS 1000

// Limits of this board's end: a longer line is skipped and counted.
#define SNR_MAX_LINE 96
#define SNR_MAX_VALUES 8

typedef void (*SnrPageHandler)(const char* key, const float* values, uint8_t count);
typedef void (*SnrFailsafeHandler)();

class SnrBoard {
 public:
  explicit SnrBoard(Stream& port) : port_(port) {}

  // Call at the end of setup(), after Serial.begin(...).
  void begin(SnrPageHandler onPage, SnrFailsafeHandler onFailsafe) {
    onPage_ = onPage;
    onFailsafe_ = onFailsafe;
    onFailsafe_();  // start with the actuators stopped
    failsafeActive = true;
    heardMs_ = nextHeartbeatMs_ = millis();
    nextReadyMs_ = heardMs_ + SNR_FAILSAFE_MS;
    port_.println(SNR_READY_LINE);
  }

  // Call in every loop(), often: each call reads what came since the last.
  void poll() {
    while (port_.available() > 0) take((char)port_.read());
    unsigned long now = millis();
    // Unsigned differences stay right when millis() wraps around (49 days).
    if (!failsafeActive && now - heardMs_ >= SNR_FAILSAFE_MS) {
      failsafeActive = true;
      failsafes++;
      onFailsafe_();
      nextReadyMs_ = now;
    }
    if (failsafeActive && (long)(now - nextReadyMs_) >= 0) {
      port_.println(SNR_READY_LINE);  // "I am here, and nobody talks to me"
      nextReadyMs_ = now + SNR_FAILSAFE_MS;
    }
    if ((long)(now - nextHeartbeatMs_) >= 0) {
      port_.print("{\"key\":\"" SNR_HEARTBEAT_KEY "\",\"data\":");
      port_.print(heartbeatsSent++);
      port_.println("}");
      nextHeartbeatMs_ = now + SNR_HEARTBEAT_MS;
    }
  }

  // Send one number as a page: {"key":"depth_m","data":2.410}.
  void send(const char* key, float value) { send(key, &value, 1, false); }

  // Send numbers as a list: {"key":"imu","data":[0.100,0.200,9.810]}.
  void send(const char* key, const float* values, uint8_t count) {
    send(key, values, count, true);
  }

  bool failsafeActive = true;       // from a failsafe until the next page line
  unsigned long failsafes = 0;      // how often it fired (not counting begin)
  unsigned long pagesReceived = 0;  // pages handed to the handler (not heartbeats)
  unsigned long badLines = 0;       // lines skipped: not pages, too long
  unsigned long heartbeatsSent = 0;

 private:
  void send(const char* key, const float* values, uint8_t count, bool list) {
    for (uint8_t i = 0; i < count; i++) {
      if (isnan(values[i]) || isinf(values[i])) return;  // JSON has no NaN: not sent
    }
    port_.print("{\"key\":\"");
    port_.print(key);
    port_.print("\",\"data\":");
    if (list) port_.print('[');
    for (uint8_t i = 0; i < count; i++) {
      if (i > 0) port_.print(',');
      port_.print(values[i], 3);
    }
    if (list) port_.print(']');
    port_.println('}');
  }

  void take(char c) {
    if (c == '\n') {
      if (!skipping_) {
        line_[length_] = '\0';
        handleLine();
      }
      skipping_ = false;
      length_ = 0;
    } else if (skipping_) {
      return;  // the rest of a line that was too long
    } else if (length_ >= SNR_MAX_LINE) {
      badLines++;
      skipping_ = true;
    } else {
      line_[length_++] = c;
    }
  }

  void handleLine() {
    if (length_ > 0 && line_[length_ - 1] == '\r') line_[--length_] = '\0';
    if (length_ == 0) return;
    if (strncmp(line_, "{\"format\":", 10) == 0) return;  // the computer's header
    if (strncmp(line_, "{\"key\":\"", 8) != 0) {
      badLines++;
      return;
    }
    char* key = line_ + 8;
    char* end = strchr(key, '"');
    if (end == NULL || end == key || memchr(key, '\\', end - key) != NULL ||
        strncmp(end, "\",\"data\":", 9) != 0) {
      badLines++;
      return;
    }
    *end = '\0';
    uint8_t count = 0;
    if (!parseNumbers(end + 9, count)) {
      badLines++;
      return;
    }
    heardMs_ = millis();
    failsafeActive = false;  // the actuators wait for the next command
    if (strcmp(key, SNR_HEARTBEAT_KEY) == 0) return;
    pagesReceived++;
    onPage_(key, values_, count);
  }

  // A number or [numbers], then the end of the page or its next field.
  bool parseNumbers(char* p, uint8_t& count) {
    bool list = (*p == '[');
    if (list) p++;
    if (list && *p == ']') {
      p++;
    } else {
      while (true) {
        char* after;
        double value = strtod(p, &after);
        if (after == p || count >= SNR_MAX_VALUES) return false;
        values_[count++] = (float)value;
        p = after;
        if (!list) break;
        if (*p == ',') {
          p++;
        } else if (*p == ']') {
          p++;
          break;
        } else {
          return false;
        }
      }
    }
    return *p == '}' || *p == ',';
  }

  Stream& port_;
  SnrPageHandler onPage_ = NULL;
  SnrFailsafeHandler onFailsafe_ = NULL;
  char line_[SNR_MAX_LINE + 1];
  uint8_t length_ = 0;
  bool skipping_ = false;
  float values_[SNR_MAX_VALUES];
  unsigned long heardMs_ = 0;
  unsigned long nextHeartbeatMs_ = 0;
  unsigned long nextReadyMs_ = 0;
};
