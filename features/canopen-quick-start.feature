Feature: The CANopen quick start through the CAN interface
  The PLC starts, reads, writes, watches and stops a Beckhoff bus coupler with
  the telegrams of the quick start, sending and receiving them only through
  the CAN interface's process image, on every profile's interface. (002, 004)

  Background:
    Given the profile's CAN interface with 8 slots
    And a Beckhoff bus coupler with node id 5 on the bus

  @NMT-001 @NMT-005 @NMT-007 @PDO-001 @COB-001
  Scenario: Started, the coupler sends its digital inputs when they change
    When the PLC sends the NMT command start to all nodes
    And 3 cycles pass
    And digital input byte 0 of the coupler becomes 0xA5
    And 3 cycles pass
    Then the PLC has received 0x185 with data A5 00

  @NMT-005 @NMT-007
  Scenario: Before the start no process data flows
    When digital input byte 0 of the coupler becomes 0xA5
    And 3 cycles pass
    Then the PLC has received 0 messages

  @PDO-003 @PDO-002 @SDO-002 @SDO-006
  Scenario: Analog inputs answer an RTR, and send by themselves after 0x6423 = 1
    When the PLC sends the NMT command start to all nodes
    And 2 cycles pass
    And analog input 0 of the coupler becomes 4660
    And 3 cycles pass
    Then the PLC has received 0 messages
    When the PLC requests the analog inputs
    And 3 cycles pass
    Then the PLC has received 0x285 with data 34 12 00 00 00 00 00 00
    When the PLC writes 0x6423:0 = 1 to the coupler by SDO
    And 3 cycles pass
    Then the PLC has received the SDO answer 60 23 64 00 00 00 00 00
    When analog input 1 of the coupler becomes -2
    And 3 cycles pass
    Then the PLC has received 0x285 with data 34 12 FE FF 00 00 00 00

  @PDO-004 @PDO-005
  Scenario: A delta (0x6426) thins out analog events
    When the PLC sends the NMT command start to all nodes
    And 2 cycles pass
    And the PLC writes 0x6423:0 = 1 to the coupler by SDO
    And 3 cycles pass
    And the PLC writes 0x6426:1 = 100 to the coupler by SDO
    And 3 cycles pass
    And analog input 0 of the coupler becomes 50
    And 3 cycles pass
    Then the PLC has received 0x585, 0x585
    When analog input 0 of the coupler becomes 150
    And 3 cycles pass
    Then the PLC has received 0x585, 0x585, 0x285

  @PDO-004 @PDO-005
  Scenario: Limits (0x6424, 0x6425) pass only values outside them
    When the PLC sends the NMT command start to all nodes
    And 2 cycles pass
    And the PLC writes 0x6423:0 = 1 to the coupler by SDO
    And the PLC writes 0x6424:1 = 1000 to the coupler by SDO
    And 3 cycles pass
    And analog input 0 of the coupler becomes 500
    And 3 cycles pass
    Then the PLC has received 0x585, 0x585
    When analog input 0 of the coupler becomes 1500
    And 3 cycles pass
    Then the PLC has received 0x585, 0x585, 0x285
    And the PLC has received 0x285 with data DC 05 00 00 00 00 00 00

  @SDO-001 @SDO-005 @SDO-009 @SDO-007 @ERR-R8
  Scenario: SDO upload and abort through the interface
    When the PLC reads 0x1001:0 from the coupler by SDO
    And 3 cycles pass
    Then the PLC has received the SDO answer 4F 01 10 00 00 00 00 00
    When the PLC reads 0x2345:0 from the coupler by SDO
    And 3 cycles pass
    Then the PLC has received the SDO answer 80 45 23 00 00 00 02 06

  @GRD-001 @GRD-002 @GRD-003 @NMT-002 @ERR-R6
  Scenario: Guarding tells the state; 0x80 ends process data, 0x02 stops
    When the PLC sends the NMT command start to all nodes
    And the PLC guards the coupler
    And 3 cycles pass
    Then the last guarding answer says operational
    When the PLC sends the NMT command enter pre-operational to all nodes
    And the PLC guards the coupler
    And 3 cycles pass
    Then the last guarding answer says pre-operational
    When the PLC sends the NMT command stop to the coupler
    And the PLC guards the coupler
    And 3 cycles pass
    Then the last guarding answer says stopped

  @HB-001 @HB-002 @HB-003 @HB-004
  Scenario: Heartbeats every 100 ms, and the coupler's loss noticed by them
    When the PLC sends the NMT command start to all nodes
    And the PLC writes 0x1017:0 = 100 to the coupler by SDO
    And 500 cycles pass
    Then the PLC receives a heartbeat every 100 ms
    When the coupler fails
    And 300 cycles pass
    Then by heartbeat the PLC notices the coupler's loss within 200 ms of 100 ms heartbeats

  @GRD-007 @GRD-001
  Scenario: The coupler's loss noticed by guarding
    When the PLC guards the coupler
    And 10 cycles pass
    Then the last guarding answer says pre-operational
    When the coupler fails
    And the PLC guards the coupler
    And 10 cycles pass
    Then by guarding the PLC notices the coupler's loss at the next request
