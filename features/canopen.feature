@model
Feature: CANopen quick start through the CAN interface
  The telegrams a PLC sends through the CAN interface to start, stop, read,
  write and watch Beckhoff CANopen bus couplers. (002, 004; rulings R6-R8)

  @NMT-001 @NMT-003 @NMT-006
  Scenario Outline: NMT telegrams
    Then the NMT command <command> for <target> is 0x000 with data <data>

    Examples:
      | command               | target    | data  |
      | start                 | all nodes | 01 00 |
      | stop                  | node 5    | 02 05 |
      | enter pre-operational | all nodes | 80 00 |
      | reset node            | node 63   | 81 3F |
      | reset communication   | node 1    | 82 01 |

  @NMT-004 @NMT-005 @GRD-003
  Scenario Outline: NMT states
    Then a node in state <from> that receives <command> is <to> and guarding reports <code>

    Examples:
      | from            | command               | to              | code |
      | pre-operational | start                 | operational     | 0x05 |
      | operational     | stop                  | stopped         | 0x04 |
      | stopped         | reset node            | pre-operational | 0x7F |
      | operational     | reset communication   | pre-operational | 0x7F |

  @COB-001 @SDO-001 @GRD-001 @ERR-R7
  Scenario Outline: Default identifiers from the node address
    Then the default identifier of <object> for node 5 is <identifier>

    Examples:
      | object              | identifier |
      | digital inputs      | 0x185      |
      | digital outputs     | 0x205      |
      | analog inputs 1-4   | 0x285      |
      | analog outputs 1-4  | 0x305      |
      | analog inputs 5-8   | 0x385      |
      | analog outputs 5-8  | 0x405      |
      | analog inputs 9-12  | 0x485      |
      | analog outputs 9-12 | 0x505      |
      | SDO responses       | 0x585      |
      | SDO requests        | 0x605      |
      | node guarding       | 0x705      |

  @SDO-003 @SDO-005
  Scenario Outline: Expedited SDO command bytes
    Then an expedited <transfer> of <n> bytes starts with <command>

    Examples:
      | transfer         | n | command |
      | upload response  | 1 | 0x4F    |
      | upload response  | 2 | 0x4B    |
      | upload response  | 3 | 0x47    |
      | upload response  | 4 | 0x43    |
      | download request | 1 | 0x2F    |
      | download request | 2 | 0x2B    |
      | download request | 3 | 0x27    |
      | download request | 4 | 0x23    |

  @PDO-003 @SDO-002 @SDO-004 @SDO-006
  Scenario: Analog inputs become event-driven with 0x6423
    Then writing 0x6423:0 = 0x01 to node 1 is 0x601 with data 22 23 64 00 01 00 00 00
    And the answer confirming it is 60 23 64 00 00 00 00 00

  @HB-002 @HB-001
  Scenario: The heartbeat is switched on by SDO and beats the state
    Then setting the heartbeat to 0xABCD ms is the SDO 22 17 10 00 CD AB 00 00
    And node 9 in state operational beats 0x709 with data 05

  @GRD-002 @GRD-003
  Scenario Outline: Guarding answers toggle bit 7
    Then node 3 answers 4 guarding requests in state <state> with <answers>

    Examples:
      | state           | answers     |
      | operational     | 05 85 05 85 |
      | pre-operational | 7F FF 7F FF |
      | stopped         | 04 84 04 84 |

  @SDO-007 @ERR-R8
  Scenario: Abort when the object does not exist
    Then aborting 0x2000:0 because the object does not exist is 80 00 20 00 00 00 02 06

  @GRD-004
  Scenario Outline: The master notices a toggle bit that did not invert
    Then a guarding answer <second> after <first> is <verdict>

    Examples:
      | first | second | verdict        |
      | 0x05  | 0x85   | accepted       |
      | 0x05  | 0x05   | a toggle error |

  @GRD-005
  Scenario Outline: Reaction time of life guarding
    Then a guard time of <guard> ms with life time factor <factor> gives <result>

    Examples:
      | guard | factor | result                        |
      | 100   | 3      | a reaction time of 300 ms     |
      | 0     | 3      | no life guarding              |

  @HB-003
  Scenario Outline: Heartbeats follow at the producer time
    Then with a producer time of <period> ms a heartbeat sent at 1 ms is followed <next>

    Examples:
      | period | next       |
      | 100    | at 101 ms  |
      | 0      | by none    |

  @PDO-002
  Scenario: Analog values travel low byte first
    Then the analog PDO of the channel values 4660 and -2 is 34 12 FE FF

  @PDO-001
  Scenario Outline: Digital PDOs carry 1 to 8 bytes
    Then a digital PDO of <n> bytes is <verdict>

    Examples:
      | n | verdict |
      | 1 | valid   |
      | 8 | valid   |
      | 9 | invalid |

  @SDO-008 @SDO-005
  Scenario Outline: Unsigned8 in D0, Unsigned16 in D0 and D1
    Then uploading <object> = <value> as Unsigned<bits> is <data>

    Examples:
      | object   | value | bits | data                    |
      | 0x1001:0 | 5     | 8    | 4F 01 10 00 05 00 00 00 |
      | 0x100C:0 | 1000  | 16   | 4B 0C 10 00 E8 03 00 00 |

  @SDO-009 @SDO-001
  Scenario: Reading an object is the upload request 0x40
    Then reading 0x1018:1 from node 5 is 0x605 with data 40 18 10 01 00 00 00 00
