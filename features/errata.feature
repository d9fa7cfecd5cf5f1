@model
Feature: Errata the suite does not copy
  Where the documents are wrong, the suite follows the correction of
  shared/RULINGS.md and says so.

  @ERR-R1
  Scenario: A length of 32 is sent with DLC 13 as 32 bytes, not 36
    Then a length of 32 is sent as 32 bytes with DLC 13
    And DLC 13 means 32 data bytes

  @ERR-R6 @NMT-002
  Scenario: 0x80 enters pre-operational, 0x02 stops
    Then a node in state operational that receives enter pre-operational is pre-operational and guarding reports 0x7F
    And a node in state operational that receives stop is stopped and guarding reports 0x04

  @ERR-R7 @SDO-001
  Scenario: The SDO request identifier is 0x600 = 1536
    Then the default identifier of SDO requests for node 1 is 0x601
    And the default identifier of SDO responses for node 1 is 0x581

  @ERR-R8 @SDO-007
  Scenario: An SDO abort carries the CiA 301 code
    Then aborting 0x6000:17 because the sub-index does not exist is 80 00 60 11 11 00 09 06
