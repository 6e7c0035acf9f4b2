// Runs SnrBoard.h on a computer. Reads commands from stdin, one per line:
//   T <ms>    set millis()        I <text>   the computer sends <text>\n
//   P         snr.poll()          S <key> <number>   snr.send(key, number)
// and prints what the board wrote ("W ...") and what it did ("PAGE ...", "STOP").
#include <iostream>
#include "Arduino.h"
#include "SnrBoard.h"

Stream port;
SnrBoard snr(port);

void onPage(const char* key, const float* values, uint8_t count) {
  std::cout << "PAGE " << key;
  for (uint8_t i = 0; i < count; i++) std::cout << " " << values[i];
  std::cout << "\n";
}

void onStop() { std::cout << "STOP\n"; }

void flush() {
  size_t end;
  while ((end = port.out.find('\n')) != std::string::npos) {
    std::cout << "W " << port.out.substr(0, end) << "\n";
    port.out.erase(0, end + 1);
  }
}

int main() {
  snr.begin(onPage, onStop);
  flush();
  std::string line;
  while (std::getline(std::cin, line)) {
    if (line.rfind("T ", 0) == 0) now_ms = std::stoul(line.substr(2));
    if (line.rfind("I ", 0) == 0) port.in += line.substr(2) + "\n";
    if (line == "P") snr.poll();
    if (line.rfind("S ", 0) == 0) {
      size_t space = line.find(' ', 2);
      snr.send(line.substr(2, space - 2).c_str(), std::stof(line.substr(space + 1)));
    }
    flush();
  }
  std::cout << "BAD " << snr.badLines << " FAILSAFES " << snr.failsafes << "\n";
}
