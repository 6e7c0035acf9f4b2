// Just enough of Arduino.h to build examples/boards/arduino/snr_board/SnrBoard.h
// on a computer, for tests/test_serial_board.py. Not a real Arduino core.
#pragma once
#include <stdint.h>
#include <stdio.h>
#include <string>

unsigned long now_ms = 0;
unsigned long millis() { return now_ms; }

class Stream {
 public:
  std::string in, out;
  int available() { return (int)in.size(); }
  int read() {
    int c = (unsigned char)in[0];
    in.erase(0, 1);
    return c;
  }
  void print(const char* s) { out += s; }
  void print(char c) { out += c; }
  void print(unsigned long n) { out += std::to_string(n); }
  void print(double x, int digits) {
    char text[64];
    snprintf(text, sizeof text, "%.*f", digits, x);
    out += text;
  }
  void println(const char* s) { out += s; out += "\r\n"; }
  void println(char c) { out += c; out += "\r\n"; }
};
