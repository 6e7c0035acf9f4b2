// A motor board for SNR: two motors on an H-bridge (e.g. L298N), driven by
// "motor" pages [left, right] in percent (-100 .. 100), stopped by the
// failsafe when the computer goes quiet. It also sends A0 ten times a second.
//
// On the computer (Python):
//   SerialLinkFactory("/dev/serial/by-id/usb-Arduino...-if00", send_keys=["motor"],
//                     ready_timeout_s=5.0, heartbeat_s=0.2, answer_timeout_s=1.0,
//                     compact=True)
#include "SnrBoard.h"

const int LEFT_PWM = 5, LEFT_DIR = 4;  // PWM pins 5 and 6 on an Uno
const int RIGHT_PWM = 6, RIGHT_DIR = 7;

SnrBoard snr(Serial);

void drive(int pwmPin, int dirPin, float percent) {
  percent = constrain(percent, -100, 100);
  digitalWrite(dirPin, percent < 0 ? LOW : HIGH);
  analogWrite(pwmPin, (int)(fabs(percent) * 255 / 100));
}

void onPage(const char* key, const float* values, uint8_t count) {
  if (strcmp(key, "motor") == 0 && count == 2) {
    drive(LEFT_PWM, LEFT_DIR, values[0]);
    drive(RIGHT_PWM, RIGHT_DIR, values[1]);
  }
}

void stopMotors() {
  drive(LEFT_PWM, LEFT_DIR, 0);
  drive(RIGHT_PWM, RIGHT_DIR, 0);
}

void setup() {
  pinMode(LEFT_PWM, OUTPUT);
  pinMode(LEFT_DIR, OUTPUT);
  pinMode(RIGHT_PWM, OUTPUT);
  pinMode(RIGHT_DIR, OUTPUT);
  Serial.begin(115200);  // the same baud rate as the SerialLinkFactory
  snr.begin(onPage, stopMotors);
}

void loop() {
  snr.poll();  // no delay() in loop(): the receive buffer holds only 64 bytes
  static unsigned long lastSentMs = 0;
  if (millis() - lastSentMs >= 100) {
    lastSentMs = millis();
    snr.send("a0", analogRead(A0));
  }
}
